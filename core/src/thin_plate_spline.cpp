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

ThinPlateSpline::ThinPlateSpline(const std::vector<Point>& src, const std::vector<Point>& dst) : centres_(src) {
  const std::size_t n = src.size();
  if (n != dst.size() || n < 3) throw std::invalid_argument("ThinPlateSpline: needs ≥ 3 matching points");
  const Eigen::Index m = static_cast<Eigen::Index>(n) + 3;
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(m, m);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, 2);
  for (std::size_t i = 0; i < n; ++i) {
    const auto ii = static_cast<Eigen::Index>(i);
    for (std::size_t j = 0; j < n; ++j) L(ii, static_cast<Eigen::Index>(j)) = tps_kernel(std::norm(src[i] - src[j]));
    L(ii, m - 3) = L(m - 3, ii) = 1.0;
    L(ii, m - 2) = L(m - 2, ii) = src[i].real();
    L(ii, m - 1) = L(m - 1, ii) = src[i].imag();
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
  Point v = affine_[0] + affine_[1] * p.real() + affine_[2] * p.imag();
  for (std::size_t i = 0; i < centres_.size(); ++i) v += weights_[i] * tps_kernel(std::norm(p - centres_[i]));
  return v;
}

}  // namespace texwarp
