// Footprint filtering from the inverse map's Jacobian on a MIP pyramid: see footprint_sampler.hpp.
#include "texwarp/core/footprint_sampler.hpp"

#include <algorithm>
#include <cmath>

namespace texwarp {
namespace {

constexpr int kMaxChannels = 16;

// The reconstruction kernels as functions of the offset in texels, and their integrals from −∞ (CDFs): bilinear's
// tent (radius 1) and bicubic's Catmull–Rom (Keys a = −1/2, radius 2), the weights sampler.cpp uses.
double tent(double u) {
  const double a = std::abs(u);
  return a < 1.0 ? 1.0 - a : 0.0;
}

double tent_cdf(double u) {
  if (u <= -1.0) return 0.0;
  if (u < 0.0) return 0.5 * (1.0 + u) * (1.0 + u);
  if (u < 1.0) return 1.0 - 0.5 * (1.0 - u) * (1.0 - u);
  return 1.0;
}

double catmull_rom(double u) {
  const double a = std::abs(u);
  if (a < 1.0) return (1.5 * a - 2.5) * a * a + 1.0;
  if (a < 2.0) return ((-0.5 * a + 2.5) * a - 4.0) * a + 2.0;
  return 0.0;
}

double catmull_rom_cdf(double u) {
  const double a = std::abs(u);
  // ∫₀ᵃ of the kernel: 0.375a⁴ − 5/6 a³ + a on [0, 1]; then −a⁴/8 + 5/6 a³ − 2a² + 2a, less its value at 1.
  const auto outer = [](double x) { return ((-0.125 * x + 5.0 / 6.0) * x - 2.0) * x * x + 2.0 * x; };
  double half = 0.5;
  if (a < 1.0) {
    half = ((0.375 * a - 5.0 / 6.0) * a * a + 1.0) * a;
  } else if (a < 2.0) {
    half = 0.375 - 5.0 / 6.0 + 1.0 + outer(a) - outer(1.0);
  }
  return u < 0.0 ? 0.5 - half : 0.5 + half;
}

// One axis of a footprint's kernel, in a level's texels: the reconstruction kernel averaged over a box of width
// `box` (the footprint less the reconstruction's and the pyramid's own spread), so that at a box of 0 it is the
// reconstruction itself.
struct AxisKernel {
  bool cubic = false;
  double box = 0.0;
  double inv_box = 0.0;
  double radius = 1.0;  // where the kernel ends

  AxisKernel(bool cubic_kernel, double stretch, double prefilter_variance) : cubic(cubic_kernel) {
    // Variances add: box²/12 + the reconstruction's (1/6 for the tent; Catmull–Rom's is close) + the pyramid's
    // prefilter = stretch²/12 + 1/12 (the footprint's box and the reconstruction's share at level 0).
    const double w2 = stretch * stretch - 1.0 - 12.0 * prefilter_variance;
    box = w2 > 1e-6 ? std::sqrt(w2) : 0.0;
    inv_box = box > 0.0 ? 1.0 / box : 0.0;
    radius = (cubic ? 2.0 : 1.0) + 0.5 * box;
  }
  double operator()(double u) const {
    if (box == 0.0) return cubic ? catmull_rom(u) : tent(u);
    const double h = 0.5 * box;
    return cubic ? (catmull_rom_cdf(u + h) - catmull_rom_cdf(u - h)) * inv_box
                 : (tent_cdf(u + h) - tent_cdf(u - h)) * inv_box;
  }
};

// The separable binomial [1 3 3 1] / 8 decimation of one row or column: out[i] from in[2i − 1 … 2i + 2], the
// border's rule beyond the ends (repeat wraps; the others clamp: the pyramid holds the image, the border's
// transparency is applied when it is read).
template <typename Get>
float binomial_tap(int i, int size, Border border, Get&& get) {
  constexpr float kWeights[4] = {0.125f, 0.375f, 0.375f, 0.125f};
  float sum = 0.0f;
  for (int k = 0; k < 4; ++k) {
    int j = 2 * i - 1 + k;
    if (border == Border::kRepeat) {
      j %= size;
      if (j < 0) j += size;
    } else {
      j = std::clamp(j, 0, size - 1);
    }
    sum += kWeights[k] * get(j);
  }
  return sum;
}

// Level l + 1 of the pyramid from level l: the binomial filter across, then down (its response at 0.4 cycles per
// texel is 0.03 where a 2×2 box's is 0.23: far less aliasing folded into the coarse levels).
Image half_size(const Image& from, Border border) {
  const int w = (from.width + 1) / 2;
  const int h = (from.height + 1) / 2;
  const int c = from.channels;
  Image across(w, from.height, c, from.alpha_channel);
  for (int y = 0; y < from.height; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int ch = 0; ch < c; ++ch) {
        across.pixel(x, y)[ch] = binomial_tap(x, from.width, border, [&](int j) { return from.pixel(j, y)[ch]; });
      }
    }
  }
  Image out(w, h, c, from.alpha_channel);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int ch = 0; ch < c; ++ch) {
        out.pixel(x, y)[ch] = binomial_tap(y, from.height, border, [&](int j) { return across.pixel(x, j)[ch]; });
      }
    }
  }
  return out;
}

}  // namespace

PixelJacobian grid_jacobian(const std::vector<Point>& positions, int width, int height, int x, int y) {
  PixelJacobian j;
  const auto at = [&](int xx, int yy) { return positions[static_cast<std::size_t>(yy) * width + xx]; };
  if (width > 1) {
    const int x0 = std::max(x - 1, 0);
    const int x1 = std::min(x + 1, width - 1);
    j.dx = (at(x1, y) - at(x0, y)) / static_cast<double>(x1 - x0);
  }
  if (height > 1) {
    const int y0 = std::max(y - 1, 0);
    const int y1 = std::min(y + 1, height - 1);
    j.dy = (at(x, y1) - at(x, y0)) / static_cast<double>(y1 - y0);
  }
  return j;
}

FootprintAxes footprint_axes(const PixelJacobian& jacobian) {
  // The ellipse K·(unit disc), K = [dx dy]: its semi-axes are the square roots of the eigenvalues of K·Kᵀ.
  const double a = jacobian.dx.real();
  const double c = jacobian.dx.imag();
  const double b = jacobian.dy.real();
  const double d = jacobian.dy.imag();
  const double m00 = a * a + b * b;
  const double m11 = c * c + d * d;
  const double m01 = a * c + b * d;
  const double half_trace = 0.5 * (m00 + m11);
  const double det = a * d - b * c;
  const double disc = std::sqrt(std::max(half_trace * half_trace - det * det, 0.0));
  const double l1 = half_trace + disc;
  const double l2 = std::max(half_trace - disc, 0.0);
  FootprintAxes axes;
  axes.major = std::sqrt(l1);
  axes.minor = std::sqrt(l2);
  Point direction = std::abs(m01) > 1e-300 ? Point(l1 - m11, m01) : (m00 >= m11 ? Point(1, 0) : Point(0, 1));
  const double norm = std::abs(direction);
  axes.major_direction = norm > 0.0 && std::isfinite(norm) ? direction / norm : Point(1, 0);
  return axes;
}

void FootprintSampler::choose_level(double minor, int levels, int& level, double& next_weight) {
  level = 0;
  next_weight = 0.0;
  if (!(minor > kMinorTexels)) return;
  const double lod = std::log2(minor / kMinorTexels);
  level = static_cast<int>(std::floor(lod));
  next_weight = lod - level;
  if (level >= levels) {
    level = levels;
    next_weight = 0.0;
  }
}

FootprintSampler::FootprintSampler(const Image& source, Interpolation interpolation, Border border)
    : source_(source), interpolation_(interpolation), border_(border) {
  for (int w = source.width, h = source.height; w > 1 || h > 1; w = (w + 1) / 2, h = (h + 1) / 2) ++max_levels_;
  levels_.resize(static_cast<std::size_t>(max_levels_));
  built_ = std::make_unique<std::once_flag[]>(static_cast<std::size_t>(max_levels_) + 1);
}

const Image& FootprintSampler::level(int l) const {
  if (l == 0) return source_;
  const auto i = static_cast<std::size_t>(l - 1);
  std::call_once(built_[i], [&] { levels_[i] = std::make_unique<Image>(half_size(level(l - 1), border_)); });
  return *levels_[i];
}

int FootprintSampler::pyramid_levels() const {
  int built = 0;
  for (const auto& l : levels_) built += l ? 1 : 0;
  return built;
}

std::size_t FootprintSampler::pyramid_bytes() const {
  std::size_t bytes = 0;
  for (const auto& l : levels_) bytes += l ? l->pixels.size() * sizeof(float) : 0;
  return bytes;
}

void FootprintSampler::filter_level(int l, Point p, const FootprintAxes& axes, double* acc) const {
  const Image& image = level(l);
  const double scale = std::ldexp(1.0, -l);  // level texels per source pixel
  // What the pyramid's binomial filters spread a level's texel by: 0.75 source px² per halving, Σ over the levels
  // above, in this level's texels².
  const double prefilter = 0.25 * (1.0 - scale * scale);
  const bool cubic = interpolation_ == Interpolation::kBicubic;
  // A footprint wider than the level itself averages all of it: the kernel is held to twice the level's size (a
  // warp that crushes the texture to a point costs a few taps on the last level, not millions).
  const double widest = 2.0 * std::max(image.width, image.height) + 4.0;
  const AxisKernel k1(cubic, std::min(axes.major * scale, widest), prefilter);
  const AxisKernel k2(cubic, std::min(axes.minor * scale, widest), prefilter);
  const double e1x = axes.major_direction.real();
  const double e1y = axes.major_direction.imag();
  const double e2x = -e1y;
  const double e2y = e1x;
  // Texel-centre coordinates of p on this level.
  const double px = p.real() * scale - 0.5;
  const double py = p.imag() * scale - 0.5;
  const double half_y = std::hypot(k1.radius * e1y, k2.radius * e2y);
  const int y0 = static_cast<int>(std::ceil(py - half_y));
  const int y1 = static_cast<int>(std::floor(py + half_y));
  const int c = image.channels;
  double sum[kMaxChannels] = {};
  double weights = 0.0;
  for (int y = y0; y <= y1; ++y) {
    const double dy = y - py;
    // The row's taps: the dx where both |u1| < r1 and |u2| < r2 (two slabs across the row), so that a thin
    // footprint at an angle visits its own area, not its bounding box.
    double lo = -1e300;
    double hi = 1e300;
    bool empty = false;
    const auto slab = [&](double ex, double ey, double r) {
      if (std::abs(ex) < 1e-12) {
        if (std::abs(ey * dy) >= r) empty = true;
        return;
      }
      const double a = (-r - ey * dy) / ex;
      const double b = (r - ey * dy) / ex;
      lo = std::max(lo, std::min(a, b));
      hi = std::min(hi, std::max(a, b));
    };
    slab(e1x, e1y, k1.radius);
    slab(e2x, e2y, k2.radius);
    if (empty || !(lo < hi)) continue;
    const int x0 = static_cast<int>(std::ceil(px + lo));
    const int x1 = static_cast<int>(std::floor(px + hi));
    const int yy = border_texel(y, image.height, border_);
    for (int x = x0; x <= x1; ++x) {
      const double dx = x - px;
      const double u1 = e1x * dx + e1y * dy;
      const double u2 = e2x * dx + e2y * dy;
      if (std::abs(u1) >= k1.radius || std::abs(u2) >= k2.radius) continue;
      const double w = k1(u1) * k2(u2);
      weights += w;
      const int xx = yy < 0 ? -1 : border_texel(x, image.width, border_);
      if (xx < 0) continue;  // outside a transparent border: reads zero
      const float* value = image.pixel(xx, yy);
      for (int ch = 0; ch < c; ++ch) sum[ch] += w * value[ch];
    }
  }
  const double inv = std::abs(weights) > 1e-12 ? 1.0 / weights : 0.0;
  for (int ch = 0; ch < c; ++ch) acc[ch] = sum[ch] * inv;
}

bool FootprintSampler::sample(Point p, const PixelJacobian& jacobian, float* out) const {
  const int c = source_.channels;
  FootprintAxes axes = footprint_axes(jacobian);
  if (!(axes.major > kMinifyingMajorAxis) || !std::isfinite(axes.major) || !std::isfinite(p.real()) ||
      !std::isfinite(p.imag()) || std::abs(p.real()) > 1e9 || std::abs(p.imag()) > 1e9) {
    sample_image(source_, p, interpolation_, border_, out);
    return false;
  }
  axes.minor = std::max(axes.minor, axes.major / kMaxAnisotropy);
  int l = 0;
  double next = 0.0;
  choose_level(axes.minor, max_levels_, l, next);
  double a[kMaxChannels];
  filter_level(l, p, axes, a);
  if (next > 0.0) {
    double b[kMaxChannels];
    filter_level(l + 1, p, axes, b);
    for (int ch = 0; ch < c; ++ch) a[ch] += next * (b[ch] - a[ch]);
  }
  for (int ch = 0; ch < c; ++ch) out[ch] = static_cast<float>(a[ch]);
  return true;
}

}  // namespace texwarp
