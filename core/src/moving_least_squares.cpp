// Similarity moving least squares (Schaefer et al. 2006, Section 2.2) in complex form: see
// moving_least_squares.hpp.
#include "texwarp/core/moving_least_squares.hpp"

#include <cmath>
#include <stdexcept>

namespace texwarp {

MovingLeastSquares::MovingLeastSquares(std::vector<Point> src, std::vector<Point> dst, double alpha)
    : src_(std::move(src)), dst_(std::move(dst)), alpha_(alpha) {
  if (src_.size() != dst_.size() || src_.size() < 2) {
    throw std::invalid_argument("MovingLeastSquares: needs ≥ 2 matching points");
  }
}

Point MovingLeastSquares::operator()(Point v) const {
  // Weights w_i = |p_i − v|^(−2α); at a feature the map is its target.
  double wsum = 0.0;
  Point p_star = 0.0;
  Point q_star = 0.0;
  thread_local std::vector<double> w;
  w.resize(src_.size());
  for (std::size_t i = 0; i < src_.size(); ++i) {
    const double d2 = std::norm(src_[i] - v);
    if (d2 == 0.0) return dst_[i];
    w[i] = std::pow(d2, -alpha_);
    wsum += w[i];
    p_star += w[i] * src_[i];
    q_star += w[i] * dst_[i];
  }
  p_star /= wsum;
  q_star /= wsum;
  // The weighted least-squares similarity about the weighted centroids: a = Σ w conj(p̂) q̂ / Σ w |p̂|² (this is
  // the paper's M/μ_s written as one complex number).
  Point num = 0.0;
  double den = 0.0;
  for (std::size_t i = 0; i < src_.size(); ++i) {
    const Point ph = src_[i] - p_star;
    const Point qh = dst_[i] - q_star;
    num += w[i] * std::conj(ph) * qh;
    den += w[i] * std::norm(ph);
  }
  const Point a = den > 0.0 ? num / den : Point(1.0, 0.0);
  return q_star + a * (v - p_star);
}

}  // namespace texwarp
