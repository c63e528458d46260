// Parity of the OpenCL backend with the CPU reference: the inverse map of every pixel of odd-sized grids and
// mapped point sets, over random feature sets (2–200 features, with gradient features, α ∈ {1.5, 2, 3}), in the
// float32 kernel (the default for tolerances ≥ 1e-3 px) and the double kernel.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "kernel_test_support.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {
namespace {

using testing::make_problem;
using testing::max_difference;
using testing::ProblemSpec;
using testing::spec;

struct GridCase {
  std::string name;
  ProblemSpec problem;
  int width;
  int height;
  OpenClPrecision precision;
  double bound;  // max |Δ| against the CPU reference, pixels
};

class GridParity : public ::testing::TestWithParam<GridCase> {};

TEST_P(GridParity, EveryPixelMatchesTheCpuReference) {
  const GridCase& c = GetParam();
  const WarpProblem problem = make_problem(c.problem);
  OpenClWarpBackend opencl(testing::opencl_options("", "", c.precision));
  CpuBackend cpu;
  const std::vector<Point> expected = cpu.inverse_map_grid(problem, c.width, c.height, {});
  const std::vector<Point> actual = opencl.inverse_map_grid(problem, c.width, c.height, {});
  ASSERT_EQ(actual.size(), static_cast<std::size_t>(c.width) * static_cast<std::size_t>(c.height));
  const double diff = max_difference(actual, expected);
  EXPECT_LE(diff, c.bound) << c.name;
  const OpenClRunStats stats = opencl.last_run_stats();
  EXPECT_EQ(stats.points, actual.size());
  EXPECT_EQ(stats.double_precision,
            c.precision == OpenClPrecision::kDouble ||
                (c.precision == OpenClPrecision::kAuto && c.problem.tolerance_px < kFloatMinTolerancePx));
  char text[32];
  std::snprintf(text, sizeof text, "%.3e", diff);
  RecordProperty("max_abs_difference_px", text);
}

constexpr auto kAuto = OpenClPrecision::kAuto;
constexpr auto kDouble = OpenClPrecision::kDouble;

INSTANTIATE_TEST_SUITE_P(
    RandomSets, GridParity,
    ::testing::Values(
        // Two features, one of them gradient: the lone positional one becomes a translation (gradient only).
        GridCase{"n2_gradient_only", spec(2, 1, 2.0, 1e-3, 97, 61, 11), 97, 61, kAuto, 1e-3},
        GridCase{"n3_alpha2", spec(3, 0, 2.0, 1e-3, 97, 61, 12), 97, 61, kAuto, 1e-3},
        GridCase{"n5_alpha1_5_gradients", spec(5, 2, 1.5, 1e-3, 97, 61, 13), 97, 61, kAuto, 1e-3},
        GridCase{"n20_alpha3_gradients", spec(20, 4, 3.0, 1e-3, 97, 61, 14), 97, 61, kAuto, 1e-3},
        GridCase{"n50_alpha2_gradients", spec(50, 10, 2.0, 1e-3, 160, 120, 15), 83, 59, kAuto, 1e-3},
        GridCase{"n200_alpha2_gradients", spec(200, 20, 2.0, 1e-3, 320, 240, 16), 33, 27, kAuto, 1e-3},
        GridCase{"n20_alpha1_5_double", spec(20, 3, 1.5, 1e-5, 97, 61, 17), 41, 37, kAuto, 1e-4},
        GridCase{"n30_alpha3_forced_double", spec(30, 5, 3.0, 1e-3, 128, 96, 18), 53, 31, kDouble, 1e-3},
        // More positional features than a column block (128): the double pair loop's rows across blocks.
        GridCase{"n160_alpha2_forced_double", spec(160, 10, 2.0, 1e-3, 320, 240, 19), 19, 13, kDouble, 1e-3}),
    [](const ::testing::TestParamInfo<GridCase>& param) { return param.param.name; });

// Random points inside and far outside the image, some clustered, and the features' own positions, both ways.
std::vector<Point> probe_points(const WarpProblem& problem, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> wide(-200.0, 400.0);
  std::normal_distribution<double> cluster(0.0, 0.7);
  std::vector<Point> points;
  points.reserve(150 + 40);
  for (int i = 0; i < 150; ++i) points.emplace_back(wide(rng), wide(rng));
  for (int i = 0; i < 40; ++i) points.emplace_back(64.0 + cluster(rng), 40.0 + cluster(rng));
  for (const Feature& f : problem.features()) {
    points.push_back(f.source);
    points.push_back(f.target);
  }
  return points;
}

TEST(PointParity, MappedPointsMatchTheCpuReferenceBothWays) {
  for (const double alpha : {1.5, 2.0, 3.0}) {
    ProblemSpec s;
    s.count = 25;
    s.gradient_count = 5;
    s.alpha = alpha;
    s.seed = 21;
    const WarpProblem problem = make_problem(s);
    OpenClWarpBackend opencl;
    CpuBackend cpu;
    for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
      std::vector<Point> expected = probe_points(problem, 5);
      std::vector<Point> actual = expected;
      map_points(cpu, problem, expected, direction);
      map_points(opencl, problem, actual, direction);
      EXPECT_LE(max_difference(actual, expected), 1e-3)
          << "alpha " << alpha << (direction == Direction::kForward ? " forward" : " inverse");
    }
  }
}

TEST(PointParity, FarFromTheOriginKeepsFloatPrecision) {
  // The same layout moved to x ≈ 100000 px, y ≈ 50000 px: float32 spacing there is 0.008 px, so positions must
  // stay relative to each point's own origin and the features' hi + lo parts for 1e-3 px.
  ProblemSpec s;
  s.count = 20;
  s.gradient_count = 3;
  s.seed = 23;
  const WarpProblem near_origin = make_problem(s);
  const Point shift(100000.0, 50000.0);
  std::vector<Feature> moved = near_origin.features();
  for (Feature& f : moved) {
    f.source += shift;
    f.target += shift;
  }
  const WarpProblem problem(moved, near_origin.options());
  OpenClWarpBackend opencl;
  CpuBackend cpu;
  std::vector<Point> expected = probe_points(near_origin, 6);
  for (Point& p : expected) p += shift;
  std::vector<Point> actual = expected;
  map_points(cpu, problem, expected, Direction::kInverse);
  map_points(opencl, problem, actual, Direction::kInverse);
  EXPECT_LE(max_difference(actual, expected), 1e-3);
}

TEST(PointParity, SinglePointAndEmptyInput) {
  const WarpProblem problem = make_problem({});
  OpenClWarpBackend opencl;
  CpuBackend cpu;
  std::vector<Point> one{Point(33.3, 44.4)};
  std::vector<Point> expected = one;
  map_points(opencl, problem, one, Direction::kInverse);
  map_points(cpu, problem, expected, Direction::kInverse);
  EXPECT_LE(max_difference(one, expected), 1e-3);
  std::vector<Point> none;
  EXPECT_NO_THROW(map_points(opencl, problem, none, Direction::kForward));
}

TEST(Accuracy, NearCollisionStaysWithinTheTolerance) {
  // Two features pass 1.4 px apart at t = 0.5 while moving 40 px: the field changes within ~0.04 of that time.
  std::vector<Feature> features;
  auto add = [&](Point s, Point t) {
    Feature f;
    f.source = s;
    f.target = t;
    features.push_back(f);
  };
  add({30, 30}, {70, 31});
  add({70, 32}, {30, 31.8});
  add({20, 10}, {24, 14});
  add({90, 60}, {85, 62});
  add({50, 70}, {52, 66});
  add({10, 60}, {14, 58});
  for (const double tolerance : {1e-2, 1e-3}) {
    WarpOptions options;
    options.prealign = Prealign::kNone;
    options.tolerance_px = tolerance;
    const WarpProblem problem(features, options);
    ASSERT_LT(problem.closest_approach().distance_px, 1.5);
    options.tolerance_px = 1e-7;
    const WarpProblem reference(features, options);
    OpenClWarpBackend opencl;
    CpuBackend cpu;
    const double err =
        max_difference(opencl.inverse_map_grid(problem, 100, 80, {}), cpu.inverse_map_grid(reference, 100, 80, {}));
    EXPECT_LE(err, tolerance) << "tolerance " << tolerance;
  }
}

TEST(PointParity, FlowJacobiansMatchTheCpuVariationalEquation) {
  ProblemSpec s;
  s.count = 15;
  s.gradient_count = 3;
  s.tolerance_px = 1e-2;  // the certified lattice's integration tolerance
  const WarpProblem problem = make_problem(s);
  OpenClWarpBackend opencl;
  CpuBackend cpu;
  std::vector<Point> points;
  for (int j = 0; j < 9; ++j) {
    for (int i = 0; i < 13; ++i) points.emplace_back(5.5 + 9.0 * i, 4.5 + 10.0 * j);
  }
  std::vector<Point> expected = points;
  std::vector<FlowJacobian> jexp(points.size());
  std::vector<FlowJacobian> jact(points.size());
  WarpOptions tight = problem.options();
  tight.tolerance_px = 1e-7;
  const WarpProblem reference(problem.features(), tight);
  cpu.flow_points_with_jacobian(reference, expected, jexp, Direction::kInverse, {});
  opencl.flow_points_with_jacobian(problem, points, jact, Direction::kInverse, {});
  EXPECT_LE(max_difference(points, expected), 1e-2);
  double worst = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double d = std::max(std::abs(jact[i].dx - jexp[i].dx), std::abs(jact[i].dy - jexp[i].dy));
    worst = std::isfinite(d) ? std::max(worst, d) : INFINITY;
  }
  // The variational equation through the tolerance-1e-2 flow in float32: what is left is how the flow's own
  // error varies from point to point (opencl_jacobian_test.cpp holds it to the CPU more closely).
  EXPECT_LE(worst, 2e-3);
}

}  // namespace
}  // namespace texwarp
