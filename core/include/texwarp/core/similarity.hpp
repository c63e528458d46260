// Similarity: a conformal affine map z ↦ a·z + b of the plane (rotation, uniform scale, translation), and its
// least-squares fit between point sets (Umeyama 1991, reflection excluded), used for pre-alignment (Section 3.3).
#pragma once

#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp {

struct Similarity {
  Point a{1.0, 0.0};  // rotation·scale
  Point b{0.0, 0.0};  // translation

  Point operator()(Point z) const { return a * z + b; }
  Similarity inverse() const { return {1.0 / a, -b / a}; }
  double scale() const { return std::abs(a); }
  double angle_rad() const { return std::arg(a); }
};

// Least-squares similarity S minimising Σ|S(src_k) − dst_k|² (the Umeyama solution restricted to proper
// rotations, in closed form for the plane). One point: the translation; none: identity. Sizes must match.
Similarity fit_similarity(const std::vector<Point>& src, const std::vector<Point>& dst);

}  // namespace texwarp
