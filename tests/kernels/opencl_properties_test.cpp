// The warp's properties on the OpenCL backend, against independent values: interpolation (f(P_i) = Q_i), the
// identity, closed-form flows (a uniform translation, a rotation with scaling), and no foldover.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "kernel_test_support.hpp"
#include "texwarp/core/constraint_residuals.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {
namespace {

using testing::make_problem;
using testing::max_difference;
using testing::ProblemSpec;

std::vector<Point> pixel_centres(int width, int height) {
  std::vector<Point> g;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) g.emplace_back(x + 0.5, y + 0.5);
  }
  return g;
}

class Interpolation : public ::testing::TestWithParam<int> {};

TEST_P(Interpolation, FeaturesLandOnTheirTargets) {
  ProblemSpec s;
  s.count = GetParam();
  s.gradient_count = GetParam() / 5;
  s.seed = static_cast<std::uint32_t>(300 + GetParam());
  const WarpProblem problem = make_problem(s);
  OpenClWarpBackend opencl;
  const ConstraintResiduals r = constraint_residuals(opencl, problem);
  ASSERT_EQ(r.per_feature.size(), problem.size());
  EXPECT_LE(r.max, 1e-3);  // NaN fails too: NaN ≤ x is false
  std::vector<Point> targets;
  for (const Feature& f : problem.features()) targets.push_back(f.target);
  std::vector<Point> sources;
  for (const Feature& f : problem.features()) sources.push_back(f.source);
  map_points(opencl, problem, targets, Direction::kInverse);
  EXPECT_LE(max_difference(targets, sources), 1e-3);
}

INSTANTIATE_TEST_SUITE_P(RandomSets, Interpolation, ::testing::Values(3, 10, 40, 120));

TEST(OpenClProperties, IdentityWhenSourcesEqualTargets) {
  std::vector<Feature> features;
  for (int i = 0; i < 12; ++i) {
    Feature f;
    f.source = f.target = Point(10.0 + 7.0 * i, 20.0 + 3.0 * (i % 5));
    if (i % 4 == 0) f.source_frame = f.target_frame = Frame{0.3 * i, 1.5};
    features.push_back(f);
  }
  const WarpProblem problem(features, WarpOptions{});
  OpenClWarpBackend opencl;
  const std::vector<Point> grid = opencl.inverse_map_grid(problem, 97, 61, {});
  EXPECT_EQ(max_difference(grid, pixel_centres(97, 61)), 0.0);
}

TEST(OpenClProperties, EqualDisplacementsGiveThatTranslation) {
  // Without pre-alignment every pair's c_ij is 0 and every term of the field is D: the map is p ↦ p + D.
  const Point d(7.25, -3.5);
  std::vector<Feature> features;
  for (int i = 0; i < 9; ++i) {
    Feature f;
    f.source = Point(12.0 + 9.0 * i, 15.0 + 4.0 * ((i * 7) % 9));
    f.target = f.source + d;
    if (i == 4) f.source_frame = f.target_frame = Frame{1.0, 2.0};
    features.push_back(f);
  }
  WarpOptions options;
  options.prealign = Prealign::kNone;
  const WarpProblem problem(features, options);
  OpenClWarpBackend opencl;
  const std::vector<Point> grid = opencl.inverse_map_grid(problem, 97, 61, {});
  std::vector<Point> expected = pixel_centres(97, 61);
  for (Point& p : expected) p -= d;
  EXPECT_LE(max_difference(grid, expected), 1e-4);
}

TEST(OpenClProperties, RotationWithScalingIsExact) {
  // Q = O + R·(P − O) for all features, no pre-alignment: every pair has c(t) = (R − 1)/(1 + t(R − 1)), so
  // v = c(t)·(p − O) everywhere and the flow is p ↦ O + (1 + t(R − 1))·(p − O): at t = 1, the similarity R.
  const Point centre(48.0, 30.0);
  const Point rotation = std::polar(1.2, 40.0 * std::numbers::pi / 180.0);
  std::vector<Feature> features;
  for (int i = 0; i < 14; ++i) {
    Feature f;
    f.source = Point(15.0 + 5.0 * i, 10.0 + 3.0 * ((i * 5) % 14));
    f.target = centre + rotation * (f.source - centre);
    features.push_back(f);
  }
  WarpOptions options;
  options.prealign = Prealign::kNone;
  const WarpProblem problem(features, options);
  OpenClWarpBackend opencl;
  const std::vector<Point> grid = opencl.inverse_map_grid(problem, 97, 61, {});
  std::vector<Point> expected = pixel_centres(97, 61);
  for (Point& p : expected) p = centre + (p - centre) / rotation;
  EXPECT_LE(max_difference(grid, expected), 1e-3);
}

TEST(OpenClProperties, NoFoldoverOnLargeRandomDeformations) {
  for (const double alpha : {1.5, 2.0, 3.0}) {
    ProblemSpec s;
    s.count = 30;
    s.gradient_count = 4;
    s.alpha = alpha;
    s.max_displacement = 45.0;
    s.seed = 77;
    const WarpProblem problem = make_problem(s);
    OpenClWarpBackend opencl;
    std::vector<Point> points;
    for (int j = 0; j < 24; ++j) {
      for (int i = 0; i < 32; ++i) points.emplace_back(2.0 + 4.0 * i, 1.5 + 4.0 * j);
    }
    // Determinants by central differences of the map at a tight tolerance (the double kernel runs). Not the
    // signed areas of 1-pixel cells of the output grid: this deformation stretches up to ~10× per pixel, so
    // such cells are not small against the map's curvature and come out inverted for the exact map too.
    for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
      const JacobianStats stats =
          summarize_determinants(warp_jacobian_determinants(opencl, problem, points, direction));
      EXPECT_EQ(stats.samples, points.size());
      EXPECT_EQ(stats.nonpositive, 0u) << "alpha " << alpha;
      EXPECT_GT(stats.min_det, 0.0) << "alpha " << alpha;
    }
  }
}

}  // namespace
}  // namespace texwarp
