// Crossing feature sets: see crossing_features.hpp.
#include "crossing_features.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace texwarp::testing {
namespace {

Feature positional(Point source, Point target) { return Feature{"", source, target}; }

}  // namespace

std::vector<Feature> random_crossing_features(int count, double size, std::uint32_t seed, bool rotation) {
  std::mt19937 rng(seed);
  const double margin = 0.1 * size;
  std::uniform_real_distribution<double> u(margin, size - margin);
  std::vector<Point> sources;
  while (static_cast<int>(sources.size()) < count) {
    const Point p(u(rng), u(rng));
    // Distinct and not too close: closer than 2 px, sources themselves would break the minimum separation.
    if (std::none_of(sources.begin(), sources.end(), [&](Point q) { return std::abs(p - q) < 2.0; })) {
      sources.push_back(p);
    }
  }
  std::vector<Point> targets = sources;
  // The features nearest to a random one (itself included), nearest first.
  auto neighbours = [&](std::size_t around, std::size_t k) {
    std::vector<std::size_t> order(sources.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(std::min(k, order.size())),
                      order.end(), [&](std::size_t x, std::size_t y) {
                        return std::abs(sources[x] - sources[around]) < std::abs(sources[y] - sources[around]);
                      });
    order.resize(std::min(k, order.size()));
    return order;
  };
  std::uniform_int_distribution<std::size_t> pick(0, sources.size() - 1);
  if (rotation) {
    // A cluster of a quarter of the features (at least 3) turned by 180° about its centroid.
    const auto cluster = neighbours(pick(rng), std::max<std::size_t>(3, sources.size() / 4));
    Point centroid = 0.0;
    for (const std::size_t i : cluster) centroid += sources[i] / static_cast<double>(cluster.size());
    for (const std::size_t i : cluster) targets[i] = 2.0 * centroid - sources[i];
  } else {
    // Neighbours swapping places (a fifth of the features, at least one pair): permuted targets.
    std::vector<bool> used(sources.size(), false);
    const std::size_t swaps = std::max<std::size_t>(1, sources.size() / 10);
    for (std::size_t s = 0, tries = 0; s < swaps && tries < 100 * swaps; ++tries) {
      const std::size_t i = pick(rng);
      const auto near = neighbours(i, 2);
      if (near.size() < 2 || used[i] || used[near[1]]) continue;
      std::swap(targets[i], targets[near[1]]);
      used[i] = used[near[1]] = true;
      ++s;
    }
  }
  std::vector<Feature> out;
  out.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) out.push_back(positional(sources[i], targets[i]));
  return out;
}

std::vector<CrossingSet> crossing_sets(double size, bool dense, double tolerance_px) {
  WarpOptions none;
  none.prealign = Prealign::kNone;
  none.tolerance_px = tolerance_px;
  WarpOptions similarity;
  similarity.tolerance_px = tolerance_px;
  const double c = 0.5 * size;
  const double s = size / 128.0;  // the shapes are drawn for 128 px
  std::vector<CrossingSet> sets;

  // Two features swapping places, two still anchors.
  sets.push_back({"swap",
                  {positional({c - 20 * s, c}, {c + 20 * s, c}), positional({c + 20 * s, c}, {c - 20 * s, c}),
                   positional({c, c - 40 * s}, {c, c - 40 * s}), positional({c, c + 40 * s}, {c, c + 40 * s})},
                  none});

  // Six features on a circle turned by 180° about its centre, four still corners.
  {
    CrossingSet set{"rotated_cluster", {}, none};
    for (int k = 0; k < 6; ++k) {
      const Point p = Point(c, c) + std::polar(18.0 * s, 2.0 * std::numbers::pi * k / 6.0 + 0.3);
      set.features.push_back(positional(p, Point(2 * c, 2 * c) - p));
    }
    for (const Point corner : {Point(15, 15), Point(113, 15), Point(15, 113), Point(113, 113)}) {
      set.features.push_back(positional(corner * s, corner * s));
    }
    sets.push_back(set);
  }

  // A 3 × 3 grid subset, permuted (pre-aligned: the permutation is no similarity).
  {
    CrossingSet set{"permuted_grid", {}, similarity};
    const int permutation[9] = {4, 0, 7, 2, 8, 1, 6, 3, 5};
    std::vector<Point> grid;
    for (int y = 0; y < 3; ++y) {
      for (int x = 0; x < 3; ++x) grid.emplace_back((34 + 30 * x) * s, (34 + 30 * y) * s);
    }
    for (int i = 0; i < 9; ++i) set.features.push_back(positional(grid[i], grid[permutation[i]]));
    sets.push_back(set);
  }

  // Three features on a line reversing their order; two anchors off the line keep S from turning the line over.
  sets.push_back(
      {"line_reversal",
       {positional({c - 24 * s, c}, {c + 24 * s, c}), positional({c, c}, {c, c + 0.01 * s}),
        positional({c + 24 * s, c}, {c - 24 * s, c}), positional({c - 10 * s, c - 40 * s}, {c - 10 * s, c - 40 * s}),
        positional({c + 10 * s, c + 40 * s}, {c + 10 * s, c + 40 * s})},
       similarity});

  // A layout mirrored about the vertical centre line (no similarity takes it there).
  {
    CrossingSet set{"mirrored", {}, none};
    // Pairs on one horizontal line cross the centre line at the same time.
    const Point pts[7] = {{30, 40}, {80, 40}, {50, 70}, {100, 70}, {40, 100}, {64, 20}, {20, 110}};
    for (const Point p : pts) set.features.push_back(positional(p * s, Point(size - p.real() * s, p.imag() * s)));
    sets.push_back(set);
  }

  // Gradient features among crossings: the permuted grid with two of its features gradient (turned, scaled).
  {
    CrossingSet set = sets[2];
    set.name = "permuted_grid_gradients";
    set.features[0].source_frame = Frame{0.2, 1.0};
    set.features[0].target_frame = Frame{0.9, 1.3};
    set.features[5].source_frame = Frame{-0.4, 1.2};
    set.features[5].target_frame = Frame{0.1, 0.9};
    sets.push_back(set);
  }

  if (dense) {
    CrossingSet set{"dense_100", random_crossing_features(100, size, 7, false), similarity};
    set.options.tolerance_px = tolerance_px;
    sets.push_back(set);
  }
  return sets;
}

}  // namespace texwarp::testing
