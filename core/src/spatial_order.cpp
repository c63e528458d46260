// Morton (Z) order of points: see spatial_order.hpp.
#include "texwarp/core/spatial_order.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

namespace texwarp {
namespace {

// Spreads the low 16 bits of x to the even bits (Morton code).
std::uint32_t spread_bits(std::uint32_t x) {
  x &= 0xffffu;
  x = (x | (x << 8)) & 0x00ff00ffu;
  x = (x | (x << 4)) & 0x0f0f0f0fu;
  x = (x | (x << 2)) & 0x33333333u;
  x = (x | (x << 1)) & 0x55555555u;
  return x;
}

}  // namespace

std::vector<std::size_t> spatial_order(std::span<const Point> points) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double x0 = kInf, y0 = kInf, x1 = -kInf, y1 = -kInf;
  for (const Point& p : points) {
    if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) continue;
    x0 = std::min(x0, p.real());
    x1 = std::max(x1, p.real());
    y0 = std::min(y0, p.imag());
    y1 = std::max(y1, p.imag());
  }
  const double extent = std::max(x1 - x0, y1 - y0);
  const double scale = extent > 0.0 && std::isfinite(extent) ? 65535.0 / extent : 0.0;
  std::vector<std::uint32_t> key(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) continue;
    const auto qx = static_cast<std::uint32_t>((p.real() - x0) * scale);
    const auto qy = static_cast<std::uint32_t>((p.imag() - y0) * scale);
    key[i] = spread_bits(qx) | (spread_bits(qy) << 1);
  }
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return key[a] < key[b]; });
  return order;
}

}  // namespace texwarp
