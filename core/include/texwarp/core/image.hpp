// Image: a float image in memory, interleaved channels, row-major from the top-left (DESIGN.md §3), colour
// channels associated (premultiplied) with alpha when there is an alpha channel.
#pragma once

#include <cstddef>
#include <vector>

namespace texwarp {

struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  int alpha_channel = -1;     // index of the alpha channel, −1 if none
  std::vector<float> pixels;  // width·height·channels values

  Image() = default;
  Image(int w, int h, int c, int alpha = -1)
      : width(w),
        height(h),
        channels(c),
        alpha_channel(alpha),
        pixels(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(c), 0.0f) {}

  float* pixel(int x, int y) {
    return pixels.data() +
           (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) *
               static_cast<std::size_t>(channels);
  }
  const float* pixel(int x, int y) const { return const_cast<Image*>(this)->pixel(x, y); }
};

}  // namespace texwarp
