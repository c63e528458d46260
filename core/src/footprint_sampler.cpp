// Footprint filtering from the inverse map's Jacobian on a MIP pyramid: see footprint_sampler.hpp.
#include "texwarp/core/footprint_sampler.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "texwarp/core/image_buffer.hpp"

namespace texwarp {
namespace {

constexpr int kMaxChannels = 16;

// The reconstruction kernels as functions of the offset in texels, and their integrals from −∞ (CDFs): bilinear's
// tent (radius 1) and bicubic's Catmull–Rom (Keys a = −1/2, radius 2), the weights sampler.cpp uses.
double tent(double u) {
  const double a = std::abs(u);
  return a < 1.0 ? 1.0 - a : 0.0;
}

// One expression for the four pieces: 1 + u is 1 − |u| for u < 0, and |u| held to 1 gives 0 and 1 beyond the ends,
// the same values as a branch per piece (GCC still branches on the sign: a bit-select was no faster).
double tent_cdf(double u) {
  const double a = std::min(std::abs(u), 1.0);
  const double tail = 0.5 * (1.0 - a) * (1.0 - a);
  return u < 0.0 ? tail : 1.0 - tail;
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
// reconstruction itself. kCubic: Catmull–Rom, else the tent (a template, so that the tap loop does not ask).
template <bool kCubic>
struct AxisKernel {
  double box = 0.0;
  double inv_box = 0.0;
  double half_box = 0.0;
  double radius = 1.0;  // where the kernel ends

  AxisKernel(double stretch, double prefilter_variance) {
    // Variances add: box²/12 + the reconstruction's (1/6 for the tent; Catmull–Rom's is close) + the pyramid's
    // prefilter = stretch²/12 + 1/12 (the footprint's box and the reconstruction's share at level 0).
    const double w2 = stretch * stretch - 1.0 - 12.0 * prefilter_variance;
    box = w2 > 1e-6 ? std::sqrt(w2) : 0.0;
    inv_box = box > 0.0 ? 1.0 / box : 0.0;
    half_box = 0.5 * box;
    radius = (kCubic ? 2.0 : 1.0) + half_box;
  }
  double operator()(double u) const {
    if (box == 0.0) return kCubic ? catmull_rom(u) : tent(u);
    return kCubic ? (catmull_rom_cdf(u + half_box) - catmull_rom_cdf(u - half_box)) * inv_box
                  : (tent_cdf(u + half_box) - tent_cdf(u - half_box)) * inv_box;
  }
};

// ceil(v) and floor(v) as int for |v| < 2³⁰ by truncation, without a call to libm on the per-row path; std::ceil
// and std::floor beyond (the same values).
constexpr double kTruncatable = 1073741824.0;

int ceil_to_int(double v) {
  if (!(std::abs(v) < kTruncatable)) return static_cast<int>(std::ceil(v));
  const int t = static_cast<int>(v);
  return static_cast<double>(t) < v ? t + 1 : t;
}

int floor_to_int(double v) {
  if (!(std::abs(v) < kTruncatable)) return static_cast<int>(std::floor(v));
  const int t = static_cast<int>(v);
  return v < static_cast<double>(t) ? t - 1 : t;
}

// ceil(v) and floor(v) of a v that is not within `guard` of an integer (then ceil = floor + 1); false where it is
// (or |v| is too large to tell by truncation).
bool ceil_floor_apart(double v, double guard, int& up, int& down) {
  if (!(std::abs(v) < kTruncatable)) return false;
  down = floor_to_int(v);
  const double f = v - down;
  if (f <= guard || f >= 1.0 - guard) return false;
  up = down + 1;
  return true;
}

// The rows a footprint's kernel spans about py: ceil(py − h), floor(py + h) with h = hypot(a, b). √(a² + b²) is
// within a few ulp of hypot: where neither end lies within 1e-12 (relative) of an integer the rows are the same, and
// hypot (a libm call, 7 % of a texture set's warp) decides only there.
void kernel_rows(double py, double a, double b, int& y0, int& y1) {
  if (a == 0.0 || b == 0.0) {  // an axis-aligned footprint: hypot is the other's magnitude, exactly
    const double h = std::abs(a) + std::abs(b);
    y0 = ceil_to_int(py - h);
    y1 = floor_to_int(py + h);
    return;
  }
  const double h = std::sqrt(a * a + b * b);
  const double guard = 1e-12 * (std::abs(py) + h + 1.0);
  int unused = 0;
  if (!ceil_floor_apart(py - h, guard, y0, unused) || !ceil_floor_apart(py + h, guard, unused, y1)) {
    const double exact = std::hypot(a, b);
    y0 = ceil_to_int(py - exact);
    y1 = floor_to_int(py + exact);
  }
}

// One of the two slabs |u| < r (u = ex·dx + ey·dy, dx and dy texel offsets from p) that bound a footprint's taps.
struct Slab {
  double ex;
  double ey;
  double r;
  bool flat;   // ex is (near) 0: the slab does not depend on dx
  double inv;  // 1 / ex

  Slab(double x, double y, double radius)
      : ex(x), ey(y), r(radius), flat(std::abs(x) < 1e-12), inv(flat ? 0.0 : 1.0 / x) {}
};

// A row's taps at offset dy: x0 … x1, the x where both |u1| < r1 and |u2| < r2 (two slabs across the row), so that a
// thin footprint at an angle visits its own area, not its bounding box; false where the row has none.
bool row_taps_exact(const Slab& s1, const Slab& s2, double px, double dy, int& x0, int& x1) {
  double lo = -1e300;
  double hi = 1e300;
  bool empty = false;
  const auto slab = [&](const Slab& s) {
    if (s.flat) {
      if (std::abs(s.ey * dy) >= s.r) empty = true;
      return;
    }
    const double a = (-s.r - s.ey * dy) / s.ex;
    const double b = (s.r - s.ey * dy) / s.ex;
    lo = std::max(lo, std::min(a, b));
    hi = std::min(hi, std::max(a, b));
  };
  slab(s1);
  slab(s2);
  if (empty || !(lo < hi)) return false;
  x0 = ceil_to_int(px + lo);
  x1 = floor_to_int(px + hi);
  return true;
}

// row_taps_exact's taps with the slabs' ends multiplied by 1 / ex instead of divided by ex (within 3 ulp): where
// neither end lies within 1e-12 (relative) of an integer the taps are the same, and the division decides only there.
bool row_taps(const Slab& s1, const Slab& s2, double px, double dy, int& x0, int& x1) {
  if (s1.flat || s2.flat) return row_taps_exact(s1, s2, px, dy, x0, x1);
  const double v1 = s1.ey * dy;
  const double v2 = s2.ey * dy;
  const double a1 = (-s1.r - v1) * s1.inv;
  const double b1 = (s1.r - v1) * s1.inv;
  const double a2 = (-s2.r - v2) * s2.inv;
  const double b2 = (s2.r - v2) * s2.inv;
  const double lo = std::max(std::min(a1, b1), std::min(a2, b2));
  const double hi = std::min(std::max(a1, b1), std::max(a2, b2));
  const double guard = 1e-12 * (std::abs(px) + std::abs(lo) + std::abs(hi) + 1.0);
  int unused = 0;
  if (!ceil_floor_apart(px + lo, guard, x0, unused) || !ceil_floor_apart(px + hi, guard, unused, x1)) {
    return row_taps_exact(s1, s2, px, dy, x0, x1);
  }
  return lo < hi;
}

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
  Image across = blank_image(w, from.height, c, from.alpha_channel);
  for (int y = 0; y < from.height; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int ch = 0; ch < c; ++ch) {
        across.pixel(x, y)[ch] = binomial_tap(x, from.width, border, [&](int j) { return from.pixel(j, y)[ch]; });
      }
    }
  }
  Image out = blank_image(w, h, c, from.alpha_channel);
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
  // √(x² + y²) rather than std::abs (hypot, a libm call): the same to a few ulp wherever the square neither overflows
  // nor underflows, and there hypot still decides.
  const double norm2 = std::norm(direction);
  const double norm = norm2 > std::numeric_limits<double>::min() && norm2 < std::numeric_limits<double>::max()
                          ? std::sqrt(norm2)
                          : std::abs(direction);
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

namespace {

// One level's footprint average (FootprintSampler::filter_level) with the interpolation and the channel count as
// template arguments (kChannels 0: any count up to kMaxChannels): the taps and their sums in the same order and with
// the same operations as a loop that asked per tap, value for value.
template <bool kCubic, int kChannels>
void filter_taps(const Image& image, Border border, double scale, Point p, const FootprintAxes& axes, double* acc) {
  // What the pyramid's binomial filters spread a level's texel by: 0.75 source px² per halving, Σ over the levels
  // above, in this level's texels².
  const double prefilter = 0.25 * (1.0 - scale * scale);
  // A footprint wider than the level itself averages all of it: the kernel is held to twice the level's size (a
  // warp that crushes the texture to a point costs a few taps on the last level, not millions).
  const double widest = 2.0 * std::max(image.width, image.height) + 4.0;
  const AxisKernel<kCubic> k1(std::min(axes.major * scale, widest), prefilter);
  const AxisKernel<kCubic> k2(std::min(axes.minor * scale, widest), prefilter);
  const double e1x = axes.major_direction.real();
  const double e1y = axes.major_direction.imag();
  const double e2x = -e1y;
  const double e2y = e1x;
  // Texel-centre coordinates of p on this level.
  const double px = p.real() * scale - 0.5;
  const double py = p.imag() * scale - 0.5;
  int y0 = 0;
  int y1 = 0;
  kernel_rows(py, k1.radius * e1y, k2.radius * e2y, y0, y1);
  const Slab slab1(e1x, e1y, k1.radius);
  const Slab slab2(e2x, e2y, k2.radius);
  const int c = kChannels > 0 ? kChannels : image.channels;
  double sum[kMaxChannels] = {};
  double weights = 0.0;
  for (int y = y0; y <= y1; ++y) {
    const double dy = y - py;
    int x0 = 0;
    int x1 = 0;
    if (!row_taps(slab1, slab2, px, dy, x0, x1)) continue;
    const int yy = y >= 0 && y < image.height ? y : border_texel(y, image.height, border);
    // The row's share of u1 and u2, and its texels: x itself where the row's taps lie inside the level.
    const double v1 = e1y * dy;
    const double v2 = e2y * dy;
    const bool inside = x0 >= 0 && x1 < image.width;
    const float* row = yy >= 0 ? image.pixel(0, yy) : nullptr;
    for (int x = x0; x <= x1; ++x) {
      const double dx = x - px;
      const double u1 = e1x * dx + v1;
      const double u2 = e2x * dx + v2;
      if (std::abs(u1) >= k1.radius || std::abs(u2) >= k2.radius) continue;
      const double w = k1(u1) * k2(u2);
      weights += w;
      if (row == nullptr) continue;  // outside a transparent border: reads zero
      const int xx = inside ? x : border_texel(x, image.width, border);
      if (xx < 0) continue;
      const float* value = row + static_cast<std::size_t>(xx) * static_cast<std::size_t>(c);
      for (int ch = 0; ch < c; ++ch) sum[ch] += w * value[ch];
    }
  }
  const double inv = std::abs(weights) > 1e-12 ? 1.0 / weights : 0.0;
  for (int ch = 0; ch < c; ++ch) acc[ch] = sum[ch] * inv;
}

template <bool kCubic>
void filter_taps_of(const Image& image, Border border, double scale, Point p, const FootprintAxes& axes, double* acc) {
  switch (image.channels) {
    case 1:
      return filter_taps<kCubic, 1>(image, border, scale, p, axes, acc);
    case 2:
      return filter_taps<kCubic, 2>(image, border, scale, p, axes, acc);
    case 3:
      return filter_taps<kCubic, 3>(image, border, scale, p, axes, acc);
    case 4:
      return filter_taps<kCubic, 4>(image, border, scale, p, axes, acc);
    default:
      return filter_taps<kCubic, 0>(image, border, scale, p, axes, acc);
  }
}

}  // namespace

void FootprintSampler::filter_level(int l, Point p, const FootprintAxes& axes, double* acc) const {
  const Image& image = level(l);
  // Level texels per source pixel: 2^−l (ldexp's value; the levels of an int-sized image are far fewer than 62).
  const double scale = l < 62 ? 1.0 / static_cast<double>(std::uint64_t{1} << l) : std::ldexp(1.0, -l);
  if (interpolation_ == Interpolation::kBicubic) {
    filter_taps_of<true>(image, border_, scale, p, axes, acc);
  } else {
    filter_taps_of<false>(image, border_, scale, p, axes, acc);
  }
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
