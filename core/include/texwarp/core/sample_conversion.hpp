// Integer samples ↔ floats as texwarp's image files hold them (OpenImageIO 2.4's conventions, which the PNG codec
// reproduces): colour associated with alpha on the integers, v · (1 / max) as float, and back by rounding half away
// from zero then unassociating on the integers. Shared by the PNG codec and the Python module's arrays.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

namespace texwarp {

// Associates colour with alpha in place on interleaved integer samples (`pixels` pixels of `channels`): c·a / max,
// truncated; with a file gamma other than 1 (a PNG's gAMA without sRGB), c·(a / max)^gamma, truncated.
template <typename T>
void associate_alpha(T* samples, std::size_t pixels, int channels, int alpha, float gamma = 1.0f) {
  constexpr unsigned kMax = std::numeric_limits<T>::max();
  if (gamma == 1.0f) {
    for (std::size_t p = 0; p < pixels; ++p, samples += channels) {
      const unsigned a = samples[alpha];
      for (int c = 0; c < channels; ++c) {
        if (c != alpha) samples[c] = static_cast<T>(samples[c] * a / kMax);
      }
    }
    return;
  }
  const auto inv_max = static_cast<float>(1.0 / kMax);
  for (std::size_t p = 0; p < pixels; ++p, samples += channels) {
    const auto associate = static_cast<float>(std::pow(static_cast<float>(samples[alpha]) * inv_max, gamma));
    for (int c = 0; c < channels; ++c) {
      if (c != alpha) samples[c] = static_cast<T>(static_cast<float>(samples[c]) * associate);
    }
  }
}

// Integer samples as float: v · (1 / max).
template <typename T>
void samples_to_float(const T* samples, std::size_t values, float* out) {
  const float scale = 1.0f / static_cast<float>(std::numeric_limits<T>::max());
  for (std::size_t i = 0; i < values; ++i) out[i] = static_cast<float>(samples[i]) * scale;
}

// A float as an integer sample: v·max rounded half away from zero, clamped (NaN → 0).
template <typename T>
T quantise(float v) {
  constexpr float kMax = std::numeric_limits<T>::max();
  float s = v * kMax;
  s += s < 0.0f ? -0.5f : 0.5f;
  if (!(s >= 0.0f)) return 0;
  return s > kMax ? static_cast<T>(kMax) : static_cast<T>(s);
}

// Unassociates colour from alpha in place on quantised integer samples: c·max / a, truncated, at most max.
template <typename T>
void unassociate_alpha(T* samples, std::size_t pixels, int channels, int alpha) {
  constexpr unsigned kMax = std::numeric_limits<T>::max();
  for (std::size_t p = 0; p < pixels; ++p, samples += channels) {
    const unsigned a = samples[alpha];
    if (a == 0 || a == kMax) continue;  // c·max / max = c
    for (int c = 0; c < channels; ++c) {
      if (c != alpha) samples[c] = static_cast<T>(std::min(kMax, samples[c] * kMax / a));
    }
  }
}

}  // namespace texwarp
