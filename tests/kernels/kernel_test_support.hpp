// Helpers of the OpenCL backend tests: comparisons that fail on NaN, and random problems whose features keep
// apart (trajectories ≥ 2 px apart: near-collisions make any DP5 error estimate unreliable, on every backend).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "random_features.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/kernels/opencl_backend.hpp"

namespace texwarp::testing {

// Largest |a[i] − b[i]|; +∞ when any value is not finite or the sizes differ (so NaN always fails).
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

struct ProblemSpec {
  int count = 20;
  int gradient_count = 0;
  double alpha = 2.0;
  double tolerance_px = 1e-3;
  double width = 128.0;  // features placed in [16, size − 16]
  double height = 96.0;
  double max_displacement = 20.0;
  std::uint32_t seed = 1;
};

inline OpenClOptions opencl_options(std::string platform, std::string device,
                                    OpenClPrecision precision = OpenClPrecision::kAuto) {
  OpenClOptions o;
  o.platform = std::move(platform);
  o.device = std::move(device);
  o.precision = precision;
  return o;
}

inline WarpProblem make_problem(const ProblemSpec& s) {
  WarpOptions options;
  options.alpha = s.alpha;
  options.tolerance_px = s.tolerance_px;
  options.min_separation_px = 2.0;
  RandomFeatureSpec spec;
  spec.count = s.count;
  spec.gradient_count = s.gradient_count;
  spec.width = s.width;
  spec.height = s.height;
  spec.max_displacement = s.max_displacement;
  spec.seed = s.seed;
  return WarpProblem(random_features(spec, options), options);
}

}  // namespace texwarp::testing
