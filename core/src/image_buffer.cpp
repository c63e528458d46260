// Image buffers with transparent huge pages where the system has them: see image_buffer.hpp.
#include "texwarp/core/image_buffer.hpp"

#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace texwarp {

void advise_huge_pages(void* data, std::size_t bytes) {
#if defined(MADV_HUGEPAGE)
  if (data == nullptr || bytes < kHugePageBufferBytes) return;
  // The whole pages inside the buffer (madvise takes page-aligned ranges); a failure only means small pages.
  const auto page = static_cast<std::uintptr_t>(::sysconf(_SC_PAGESIZE));
  auto* const bytes_at = static_cast<char*>(data);
  const auto begin = reinterpret_cast<std::uintptr_t>(bytes_at);
  const std::uintptr_t first = (begin + page - 1) / page * page;
  const std::uintptr_t last = (begin + bytes) / page * page;
  if (last > first) ::madvise(bytes_at + (first - begin), last - first, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

void reserve_pixels(Image& image, std::size_t values) {
  image.pixels.reserve(values);
  advise_huge_pages(image.pixels.data(), image.pixels.capacity() * sizeof(float));
}

Image blank_image(int width, int height, int channels, int alpha_channel) {
  Image image;
  image.width = width;
  image.height = height;
  image.channels = channels;
  image.alpha_channel = alpha_channel;
  const std::size_t values =
      static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * static_cast<std::size_t>(channels);
  reserve_pixels(image, values);
  image.pixels.resize(values, 0.0f);
  return image;
}

}  // namespace texwarp
