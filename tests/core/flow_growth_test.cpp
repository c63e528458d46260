// The growth scale of planned maps (flow_growth.hpp): the chain's growth against its sum written out, the probe's
// scale against segment Jacobians taken by central differences of pathlines (not the variational equation), copies
// sharing it, and the permuted grid with gradient features within 0.05 px at every pixel against the CPU at 1e-9 px
// (1.28× off before it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "crossing_features.hpp"
#include "point_compare.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/flow_growth.hpp"
#include "texwarp/core/pathline.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {
namespace {

using testing::max_difference;

TEST(FlowGrowth, TheChainsGrowthIsEverySegmentsErrorGrownThroughTheRest) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.3, 4.0);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<double> sigma(1 + trial % 6);
    for (double& s : sigma) s = u(rng);
    double growth = 0.0;
    for (const double s : sigma) growth = chain_growth_step(growth, s);
    double expected = 0.0;  // Σ_m Π_{r=m..K} max(1, σ_r)
    for (std::size_t m = 0; m < sigma.size(); ++m) {
      double product = 1.0;
      for (std::size_t r = m; r < sigma.size(); ++r) product *= std::max(1.0, sigma[r]);
      expected += product;
    }
    EXPECT_NEAR(growth, expected, 1e-12 * expected);
  }
}

TEST(FlowGrowth, TheScaleFollowsTheSegmentsJacobiansByDifferences) {
  const testing::CrossingSet set = testing::crossing_sets(96.0, false, 1e-3).back();
  ASSERT_EQ(set.name, "permuted_grid_gradients");
  WarpOptions options = set.options;
  options.tolerance_px = 1e-9;
  const WarpProblem tight(set.features, options);
  ASSERT_EQ(tight.segments().size(), 4u);
  CpuBackend cpu;
  // Each segment's W⁻¹ by central differences of pathlines at 1e-9 px (h = 1e-4 px), along each probe point's path.
  const double h = 1e-4;
  std::vector<Point> points = growth_probe_points(tight, Direction::kInverse);
  std::vector<double> growth(points.size(), 0.0);
  for (std::size_t step = 0; step < tight.segments().size(); ++step) {
    const std::size_t segment = tight.segments().size() - 1 - step;
    std::vector<Point> around;
    for (const Point& p : points) {
      for (const Point d : {Point(h, 0), Point(-h, 0), Point(0, h), Point(0, -h)}) around.push_back(p + d);
    }
    cpu.flow_segment(tight, segment, around, Direction::kInverse, {});
    cpu.flow_segment(tight, segment, points, Direction::kInverse, {});
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Point dx = (around[4 * i] - around[4 * i + 1]) / (2 * h);
      const Point dy = (around[4 * i + 2] - around[4 * i + 3]) / (2 * h);
      const double f2 = std::norm(dx) + std::norm(dy);
      const double det = dx.real() * dy.imag() - dx.imag() * dy.real();
      const double sigma = std::sqrt(0.5 * (f2 + std::sqrt(std::max(0.0, f2 * f2 - 4 * det * det))));
      growth[i] = chain_growth_step(growth[i], sigma);
    }
  }
  const double worst = *std::max_element(growth.begin(), growth.end());
  EXPECT_GT(worst, 1.0 / kLocalErrorFraction);  // the chain grows errors beyond the integration's room
  options.tolerance_px = 0.05;
  const WarpProblem problem(set.features, options);
  const double scale = measure_growth_scale(cpu, problem, Direction::kInverse, {});
  EXPECT_NEAR(scale, (1.0 / kLocalErrorFraction) / worst, 0.02 * scale);
  // Measured once, shared with the problem's copies, and in the pathlines' tolerance.
  EXPECT_EQ(problem.growth_scale(Direction::kInverse), 1.0);
  const WarpProblem copy = problem.with_tolerance(0.01);
  ensure_growth_scale(cpu, problem, Direction::kInverse, {});
  EXPECT_DOUBLE_EQ(copy.growth_scale(Direction::kInverse), problem.growth_scale(Direction::kInverse));
  EXPECT_NEAR(problem.growth_scale(Direction::kInverse), scale, 0.02 * scale);
  EXPECT_DOUBLE_EQ(problem.pathline_tolerance_px(Direction::kInverse),
                   0.05 * std::abs(problem.prealignment().a) * problem.growth_scale(Direction::kInverse));
  EXPECT_EQ(problem.growth_scale(Direction::kForward), 1.0);  // not measured yet
}

TEST(FlowGrowth, OneSegmentIsNotScaled) {
  const testing::CrossingSet set = testing::crossing_sets(96.0, false, 1e-3).front();
  std::vector<Feature> apart = {set.features[0]};  // one feature: straight, one segment
  const WarpProblem problem(apart, set.options);
  ASSERT_EQ(problem.segments().size(), 1u);
  CpuBackend cpu;
  EXPECT_EQ(measure_growth_scale(cpu, problem, Direction::kInverse, {}), 1.0);
  std::vector<Point> points = {Point(10, 10)};
  map_points(cpu, problem, points, Direction::kInverse);
  EXPECT_EQ(problem.growth_scale(Direction::kInverse), 1.0);
}

// Every pixel of the permuted grid with gradient features (4 segments, each stretching by 2–3 where the error
// grows most) against the CPU at 1e-9 px: before the growth scale it missed 0.05 px by 1.28× (0.064 px).
TEST(FlowGrowth, ThePermutedGridWithGradientsMeetsTheToleranceAtEveryPixel) {
  const testing::CrossingSet set = testing::crossing_sets(96.0, false, 1e-3).back();
  ASSERT_EQ(set.name, "permuted_grid_gradients");
  WarpOptions options = set.options;
  options.tolerance_px = 1e-9;
  CpuBackend cpu;
  std::vector<Point> truth;
  for (int y = 0; y < 96; ++y) {
    for (int x = 0; x < 96; ++x) truth.emplace_back(x + 0.5, y + 0.5);
  }
  map_points(cpu, WarpProblem(set.features, options), truth, Direction::kInverse);
  for (const double tolerance : {1e-2, 5e-2}) {
    options.tolerance_px = tolerance;
    const WarpProblem problem(set.features, options);
    EXPECT_LE(max_difference(cpu.inverse_map_grid(problem, 96, 96, {}), truth), tolerance)
        << "at " << tolerance << " px, growth scale " << problem.growth_scale(Direction::kInverse);
    EXPECT_LT(problem.growth_scale(Direction::kInverse), 0.2);
  }
}

}  // namespace
}  // namespace texwarp
