// Comparisons of point sets for the test suites, made so that NaN always fails.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp::testing {

// Largest |a[i] − b[i]|; +∞ when any value is not finite or the sizes differ.
inline double max_difference(const std::vector<Point>& a, const std::vector<Point>& b) {
  if (a.size() != b.size()) return INFINITY;
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = std::abs(a[i] - b[i]);
    if (!std::isfinite(d)) return INFINITY;
    worst = std::max(worst, d);
  }
  return worst;
}

}  // namespace texwarp::testing
