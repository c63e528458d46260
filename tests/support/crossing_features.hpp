// Feature sets whose straight trajectories collide (refused before trajectories were planned, issue 13): the
// named shapes the tests run, and random crossing sets for the trajectory benchmark.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "texwarp/core/feature.hpp"
#include "texwarp/core/warp_options.hpp"

namespace texwarp::testing {

struct CrossingSet {
  std::string name;
  std::vector<Feature> features;
  WarpOptions options;
};

// In a size × size image: two features swapping; a cluster rotated by 180°; a permuted grid subset; three on a
// line reversing order; a mirrored layout; gradient features among crossings; with `dense`, also 100 features
// with many crossings. Each one's straight trajectories (after pre-alignment) come closer than the minimum.
std::vector<CrossingSet> crossing_sets(double size, bool dense, double tolerance_px);

// `count` random sources at least 2 px apart in the middle 80 % of size², their targets: neighbours swapping places
// (a fifth of the features; rotation = false), or a cluster of a quarter of them turned by 180° about its centroid
// (rotation = true); the others stay.
std::vector<Feature> random_crossing_features(int count, double size, std::uint32_t seed, bool rotation);

}  // namespace texwarp::testing
