// Bilinear and bicubic sampling with border modes: see sampler.hpp.
#include "texwarp/core/sampler.hpp"

#include <cmath>

#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

// Catmull–Rom weights (Keys' cubic with a = −1/2) for fractional offset f ∈ [0, 1).
inline void cubic_weights(double f, double w[4]) {
  const double f2 = f * f;
  const double f3 = f2 * f;
  w[0] = -0.5 * f3 + f2 - 0.5 * f;
  w[1] = 1.5 * f3 - 2.5 * f2 + 1.0;
  w[2] = -1.5 * f3 + 2.0 * f2 + 0.5 * f;
  w[3] = 0.5 * f3 - 0.5 * f2;
}

template <int kTaps>
void sample_separable(const Image& image, const double* wx, const double* wy, int x0, int y0, Border border,
                      float* out) {
  const int c = image.channels;
  double acc[16] = {};
  for (int j = 0; j < kTaps; ++j) {
    const int yy = border_texel(y0 + j, image.height, border);
    if (yy < 0 || wy[j] == 0.0) continue;
    for (int i = 0; i < kTaps; ++i) {
      const int xx = border_texel(x0 + i, image.width, border);
      if (xx < 0 || wx[i] == 0.0) continue;
      const double w = wx[i] * wy[j];
      const float* px = image.pixel(xx, yy);
      for (int ch = 0; ch < c; ++ch) acc[ch] += w * px[ch];
    }
  }
  for (int ch = 0; ch < c; ++ch) out[ch] = static_cast<float>(acc[ch]);
}

}  // namespace

int border_texel(int i, int size, Border border) {
  if (i >= 0 && i < size) return i;
  switch (border) {
    case Border::kClamp:
      return i < 0 ? 0 : size - 1;
    case Border::kRepeat: {
      const int m = i % size;
      return m < 0 ? m + size : m;
    }
    case Border::kTransparent:
      break;
  }
  return -1;
}

void sample_image(const Image& image, Point p, Interpolation interpolation, Border border, float* out) {
  const int c = image.channels;
  const double x = p.real() - 0.5;  // texel-centre coordinates
  const double y = p.imag() - 0.5;
  if (!std::isfinite(x) || !std::isfinite(y) || std::abs(x) > 1e9 || std::abs(y) > 1e9) {
    for (int ch = 0; ch < c; ++ch) out[ch] = 0.0f;
    return;
  }
  const double fx = std::floor(x);
  const double fy = std::floor(y);
  const double tx = x - fx;
  const double ty = y - fy;
  const int ix = static_cast<int>(fx);
  const int iy = static_cast<int>(fy);
  if (interpolation == Interpolation::kBilinear) {
    const double wx[2] = {1.0 - tx, tx};
    const double wy[2] = {1.0 - ty, ty};
    sample_separable<2>(image, wx, wy, ix, iy, border, out);
  } else {
    double wx[4];
    double wy[4];
    cubic_weights(tx, wx);
    cubic_weights(ty, wy);
    sample_separable<4>(image, wx, wy, ix - 1, iy - 1, border, out);
  }
}

}  // namespace texwarp
