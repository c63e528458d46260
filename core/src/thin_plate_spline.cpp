// Thin-plate spline interpolation (Bookstein 1989): see thin_plate_spline.hpp.
#include "texwarp/core/thin_plate_spline.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>

namespace texwarp {
namespace {

// The TPS kernel U(r) = r² log r, written with r²: ½·r²·log r².
inline double tps_kernel(double r2) { return r2 > 0.0 ? 0.5 * r2 * std::log(r2) : 0.0; }

}  // namespace

// The spline is fitted in coordinates centred on the sources' centroid and scaled by their RMS radius. The
// interpolant does not change (a thin-plate spline commutes with similarities: the r²·log s² term a scaling
// adds is cancelled by the side conditions Σw = 0, Σw·p = 0), but in pixels the kernel entries reach ~1e7 beside
// the affine block's ones, and the LU's rank test then calls a well-posed system singular.
ThinPlateSpline::ThinPlateSpline(const std::vector<Point>& src, const std::vector<Point>& dst) {
  const std::size_t n = src.size();
  if (n != dst.size() || n < 3) throw std::invalid_argument("ThinPlateSpline: needs ≥ 3 matching points");
  Point centroid(0.0);
  for (const Point& p : src) centroid += p;
  origin_ = centroid / static_cast<double>(n);
  double spread = 0.0;
  for (const Point& p : src) spread += std::norm(p - origin_);
  spread = std::sqrt(spread / static_cast<double>(n));
  if (!(spread > 0.0) || !std::isfinite(spread)) {
    throw std::invalid_argument("ThinPlateSpline: points are collinear or repeated");
  }
  scale_ = 1.0 / spread;
  centres_.reserve(n);
  for (const Point& p : src) centres_.push_back((p - origin_) * scale_);

  const Eigen::Index m = static_cast<Eigen::Index>(n) + 3;
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(m, m);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, 2);
  for (std::size_t i = 0; i < n; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    for (std::size_t j = 0; j < n; ++j) {
      L(ii, static_cast<Eigen::Index>(j)) = tps_kernel(std::norm(centres_[i] - centres_[j]));
    }
    L(ii, m - 3) = L(m - 3, ii) = 1.0;
    L(ii, m - 2) = L(m - 2, ii) = centres_[i].real();
    L(ii, m - 1) = L(m - 1, ii) = centres_[i].imag();
    rhs(ii, 0) = dst[i].real();
    rhs(ii, 1) = dst[i].imag();
  }
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(L);
  if (!lu.isInvertible()) throw std::invalid_argument("ThinPlateSpline: points are collinear or repeated");
  const Eigen::MatrixXd sol = lu.solve(rhs);
  weights_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    weights_[i] = Point(sol(static_cast<Eigen::Index>(i), 0), sol(static_cast<Eigen::Index>(i), 1));
  }
  for (int k = 0; k < 3; ++k) affine_[k] = Point(sol(m - 3 + k, 0), sol(m - 3 + k, 1));
}

Point ThinPlateSpline::operator()(Point p) const {
  const Point q = (p - origin_) * scale_;
  Point v = affine_[0] + affine_[1] * q.real() + affine_[2] * q.imag();
  for (std::size_t i = 0; i < centres_.size(); ++i) v += weights_[i] * tps_kernel(std::norm(q - centres_[i]));
  return v;
}

}  // namespace texwarp
