// Helpers of the OpenCL backend tests: comparisons that fail on NaN, and random valid problems (at the default
// minimum separation: passes closer than a pixel remain, where both backends cap their steps).
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "point_compare.hpp"
#include "random_features.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/kernels/opencl_backend.hpp"

namespace texwarp::testing {

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

// The spec of a random problem in one line (the parameterised suites' tables).
inline ProblemSpec spec(int count, int gradients, double alpha, double tolerance, double width, double height,
                        std::uint32_t seed) {
  ProblemSpec s;
  s.count = count;
  s.gradient_count = gradients;
  s.alpha = alpha;
  s.tolerance_px = tolerance;
  s.width = width;
  s.height = height;
  s.seed = seed;
  return s;
}

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
