// Buffers of a value per pixel of whole images (a map's decode, a warp's output, the output grid's map): reserved where
// the system can back them with transparent huge pages, so that filling a 2048² map takes a few dozen page faults
// instead of thousands.
#pragma once

#include <cstddef>
#include <vector>

#include "texwarp/core/image.hpp"

namespace texwarp {

// Reserves image.pixels for `values` floats (address space: nothing is committed before it is written) and, for a
// buffer of at least kHugePageBufferBytes on Linux, advises the kernel to back it with transparent huge pages
// (madvise MADV_HUGEPAGE; where THP is off it changes nothing). std::bad_alloc as std::vector::reserve.
inline constexpr std::size_t kHugePageBufferBytes = std::size_t{8} << 20;
void reserve_pixels(Image& image, std::size_t values);

// The advice alone, for the whole pages of [data, data + bytes) when bytes ≥ kHugePageBufferBytes (before anything is
// written there: pages already touched stay small).
void advise_huge_pages(void* data, std::size_t bytes);

// A buffer of `count` value-initialised T (zero for arithmetic types and Point) reserved as reserve_pixels reserves.
template <class T>
std::vector<T> huge_page_vector(std::size_t count) {
  std::vector<T> v;
  v.reserve(count);
  advise_huge_pages(v.data(), v.capacity() * sizeof(T));
  v.resize(count);
  return v;
}

// Image(width, height, channels, alpha_channel), zero-filled as that constructor makes it, with its buffer reserved
// by reserve_pixels.
Image blank_image(int width, int height, int channels, int alpha_channel = -1);

}  // namespace texwarp
