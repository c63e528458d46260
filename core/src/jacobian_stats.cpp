// Discrete Jacobian determinants of a gridded map: see jacobian_stats.hpp.
#include "texwarp/core/jacobian_stats.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace texwarp {
namespace {

inline double cross(Point u, Point v) { return u.real() * v.imag() - u.imag() * v.real(); }

}  // namespace

JacobianStats grid_jacobian_stats(const std::vector<Point>& mapped, int nx, int ny, double step) {
  if (nx < 2 || ny < 2 || mapped.size() != static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) ||
      !(step > 0.0)) {
    throw std::invalid_argument("grid_jacobian_stats: need an nx×ny grid with nx, ny ≥ 2 and step > 0");
  }
  JacobianStats s;
  s.min_det = std::numeric_limits<double>::infinity();
  s.max_det = -std::numeric_limits<double>::infinity();
  const double area = step * step;
  auto add = [&s](double det) {
    // NaN counts as a fold: it must never pass as a valid determinant.
    if (!(det > 0.0)) ++s.nonpositive;
    if (det < s.min_det || det != det) s.min_det = det;
    if (det > s.max_det) s.max_det = det;
    ++s.samples;
  };
  for (int j = 0; j + 1 < ny; ++j) {
    for (int i = 0; i + 1 < nx; ++i) {
      const Point p00 = mapped[static_cast<std::size_t>(j) * nx + i];
      const Point p10 = mapped[static_cast<std::size_t>(j) * nx + i + 1];
      const Point p01 = mapped[static_cast<std::size_t>(j + 1) * nx + i];
      const Point p11 = mapped[static_cast<std::size_t>(j + 1) * nx + i + 1];
      add(cross(p10 - p00, p01 - p00) / area);
      add(cross(p01 - p11, p10 - p11) / area);
    }
  }
  return s;
}

}  // namespace texwarp
