// Random feature sets for tests and benchmarks: positional and gradient features inside an image, displaced at random,
// drawn one at a time so that the whole set is valid with straight trajectories (no duplicates, no collisions).
#pragma once

#include <cstdint>
#include <vector>

#include "texwarp/core/feature.hpp"
#include "texwarp/core/warp_options.hpp"

namespace texwarp::testing {

struct RandomFeatureSpec {
  int count = 20;          // features in all
  int gradient_count = 0;  // of which gradient features
  double width = 512.0;    // sources and targets inside [margin, size − margin]
  double height = 512.0;
  double margin = 16.0;
  double max_displacement = 40.0;  // |Q − P| ≤ this (before the set's common similarity)
  double max_rotation_deg = 30.0;  // gradient frames: |Δangle| ≤ this
  double max_log_scale = 0.4;      // gradient frames: |ln(s1/s0)| ≤ this
  std::uint32_t seed = 1;
};

std::vector<Feature> random_features(const RandomFeatureSpec& spec, const WarpOptions& options);

}  // namespace texwarp::testing
