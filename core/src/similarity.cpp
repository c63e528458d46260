// Least-squares similarity between planar point sets (Umeyama 1991): see similarity.hpp.
#include "texwarp/core/similarity.hpp"

#include <stdexcept>

namespace texwarp {

Similarity fit_similarity(const std::vector<Point>& src, const std::vector<Point>& dst) {
  if (src.size() != dst.size()) throw std::invalid_argument("fit_similarity: point sets differ in size");
  const std::size_t n = src.size();
  if (n == 0 || src == dst) return {};  // identical sets: exactly the identity (the identity property)
  Point src_mean = 0.0;
  Point dst_mean = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    src_mean += src[k];
    dst_mean += dst[k];
  }
  src_mean /= static_cast<double>(n);
  dst_mean /= static_cast<double>(n);
  // In complex form the minimiser over a = c·R (proper rotations only) of Σ|a·x_k − y_k|² for centred x, y is
  // a = Σ conj(x_k)·y_k / Σ|x_k|², which is Umeyama's c·R with det R = +1.
  Point cross = 0.0;
  double norm = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const Point x = src[k] - src_mean;
    const Point y = dst[k] - dst_mean;
    cross += std::conj(x) * y;
    norm += std::norm(x);
  }
  Similarity s;
  if (norm > 0.0 && std::abs(cross) > 0.0) {
    s.a = cross / norm;
  }
  s.b = dst_mean - s.a * src_mean;
  return s;
}

}  // namespace texwarp
