// libFuzzer target: the image header gate (texwarp::read_image_header with texwarpd's default limits) on bytes
// written to a temporary file; the first byte picks the extension: png, jpg, tif, exr, or none, as texwarpd stores
// blobs and inline images (the reader their first bytes name). PNG goes through core's libpng reader, the rest through
// the OpenImageIO module (build-fuzz/lib/texwarp). A small image that passes the gate is also read in full
// (read_image), as a job would. InputError is the expected outcome for bad input.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace {

constexpr const char* kExtensions[] = {".png", ".jpg", ".tif", ".exr", ""};
// Images at most this many values (width × height × channels) are decoded in full after the header gate.
constexpr long long kMaxDecodedValues = 1LL << 18;

[[noreturn]] void finding(const char* what, std::string_view text) {
  std::fprintf(stderr, "fuzz_image_header finding: %s\n%.*s\n", what, static_cast<int>(text.size()), text.data());
  std::abort();
}

// One file per extension ("" or ".png"...) and process (libFuzzer's -jobs run several processes), under TMPDIR.
std::string temporary_image_path(const char* extension) {
  std::error_code ec;
  std::filesystem::path folder = std::filesystem::temp_directory_path(ec);
  if (ec) folder = "/tmp";
  return (folder / ("texwarp-fuzz-image-" + std::to_string(getpid()) + extension)).string();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const char* extension = kExtensions[data[0] % std::size(kExtensions)];
  const std::string path = temporary_image_path(extension);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    if (!out) finding("cannot write the temporary image", path);
  }
  const texwarp::ImageLimits limits;  // texwarpd's defaults (--max-image-megapixels, --max-image-side, ...)
  try {
    const texwarp::ImageHeader header = texwarp::read_image_header(path, limits);
    if (header.width <= 0 || header.height <= 0 || header.width > limits.max_dimension ||
        header.height > limits.max_dimension || header.channels < 1 || header.channels > limits.max_channels ||
        static_cast<long long>(header.width) * header.height > limits.max_pixels) {
      finding("read_image_header passed a header outside the limits", path);
    }
    if (static_cast<long long>(header.width) * header.height * header.channels <= kMaxDecodedValues) {
      texwarp::ImageHeader decoded;
      const texwarp::Image image = texwarp::read_image(path, limits, &decoded);
      if (image.width != header.width || image.height != header.height || image.channels != header.channels) {
        finding("read_image disagrees with read_image_header", path);
      }
    }
  } catch (const texwarp::InputError& error) {
    const std::string message = texwarp::proto::utf8_prefix(error.what(), 1024);
    if (!texwarp::proto::is_valid_utf8(message)) finding("utf8_prefix(InputError) is not valid UTF-8", message);
  }
  std::remove(path.c_str());
  return 0;
}
