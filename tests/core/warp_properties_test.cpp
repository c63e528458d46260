// The warp's properties (paper Section 2.1) on the CPU reference: interpolation, identity, round trip,
// gradient constraints, closed-form cases, and foldover-freedom where a thin-plate spline folds.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "random_features.hpp"
#include "texwarp/core/constraint_residuals.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/thin_plate_spline.hpp"

namespace texwarp {
namespace {

std::vector<Point> mapped(const WarpProblem& problem, std::vector<Point> points, Direction direction) {
  CpuBackend cpu;
  map_points(cpu, problem, points, direction);
  return points;
}

std::vector<Point> grid_points(double x0, double y0, double step, int nx, int ny) {
  std::vector<Point> g;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) g.emplace_back(x0 + i * step, y0 + j * step);
  }
  return g;
}

struct InterpolationCase {
  int count;
  int gradient_count;
  Prealign prealign;
};

class Interpolation : public ::testing::TestWithParam<InterpolationCase> {};

TEST_P(Interpolation, FeaturesLandOnTheirTargets) {
  const auto c = GetParam();
  WarpOptions options;
  options.prealign = c.prealign;
  options.tolerance_px = 1e-7;
  testing::RandomFeatureSpec spec;
  spec.count = c.count;
  spec.gradient_count = c.gradient_count;
  spec.seed = static_cast<std::uint32_t>(100 + c.count);
  const WarpProblem problem(testing::random_features(spec, options), options);
  CpuBackend cpu;
  const ConstraintResiduals r = constraint_residuals(cpu, problem);
  EXPECT_LE(r.max, 1e-6) << c.count << " features";
  // And the inverse map takes each target back to its source.
  std::vector<Point> targets;
  for (const Feature& f : problem.features()) targets.push_back(f.target);
  const auto back = mapped(problem, targets, Direction::kInverse);
  for (std::size_t i = 0; i < back.size(); ++i) {
    EXPECT_LE(std::abs(back[i] - problem.features()[i].source), 1e-6) << i;
  }
}

INSTANTIATE_TEST_SUITE_P(
    RandomSets, Interpolation,
    ::testing::Values(InterpolationCase{2, 0, Prealign::kSimilarity}, InterpolationCase{2, 0, Prealign::kNone},
                      InterpolationCase{3, 0, Prealign::kNone}, InterpolationCase{10, 3, Prealign::kSimilarity},
                      InterpolationCase{25, 0, Prealign::kNone}, InterpolationCase{50, 5, Prealign::kSimilarity},
                      InterpolationCase{100, 0, Prealign::kSimilarity}, InterpolationCase{200, 10, Prealign::kNone},
                      InterpolationCase{200, 0, Prealign::kSimilarity}),
    [](const ::testing::TestParamInfo<InterpolationCase>& param_info) {
      return std::to_string(param_info.param.count) + "_features_" + std::to_string(param_info.param.gradient_count) +
             "_gradient_" + (param_info.param.prealign == Prealign::kSimilarity ? "prealigned" : "raw");
    });

TEST(WarpProperties, IdentityWhenSourcesEqualTargets) {
  std::vector<Feature> f;
  for (int k = 0; k < 12; ++k) {
    const Point p(20.0 + 37.0 * k, 300.0 - 19.0 * k);
    f.push_back({"", p, p});
  }
  f.push_back({"g", {400, 400}, {400, 400}, Frame{0.3, 2.0}, Frame{0.3, 2.0}});
  for (const Prealign prealign : {Prealign::kSimilarity, Prealign::kNone}) {
    WarpOptions o;
    o.prealign = prealign;
    const WarpProblem problem(f, o);
    const auto g = grid_points(-10.5, 3.25, 17.0, 20, 20);
    EXPECT_EQ(mapped(problem, g, Direction::kForward), g);
    EXPECT_EQ(mapped(problem, g, Direction::kInverse), g);
  }
}

// Random sets whose trajectories stay at least this far apart: the map stays moderately distorted, so that
// errors of one map are not magnified beyond the tolerance by the other's Jacobian.
WarpOptions well_separated(WarpOptions o) {
  o.min_separation_px = 20.0;
  return o;
}

TEST(WarpProperties, RoundTripWithinTolerance) {
  for (const double tol : {0.05, 0.01, 0.001}) {
    WarpOptions options;
    options.tolerance_px = tol;
    testing::RandomFeatureSpec spec;
    spec.count = 30;
    spec.gradient_count = 4;
    spec.max_displacement = 60.0;
    spec.seed = 5;
    const WarpProblem problem(testing::random_features(spec, well_separated(options)), options);
    const auto g = grid_points(0.5, 0.5, 16.0, 33, 33);
    const auto back = mapped(problem, mapped(problem, g, Direction::kForward), Direction::kInverse);
    double worst = 0.0;
    for (std::size_t i = 0; i < g.size(); ++i) worst = std::max(worst, std::abs(back[i] - g[i]));
    EXPECT_LE(worst, tol) << "tolerance " << tol;
  }
}

TEST(WarpProperties, IntegrationErrorWithinTolerance) {
  // The same map at a tolerance 10⁴ times tighter stands in for the exact one.
  WarpOptions options;
  options.tolerance_px = 0.01;
  testing::RandomFeatureSpec spec;
  spec.count = 40;
  spec.gradient_count = 4;
  spec.max_displacement = 60.0;
  spec.seed = 9;
  const auto features = testing::random_features(spec, options);
  const WarpProblem coarse(features, options);
  options.tolerance_px = 1e-6;
  const WarpProblem fine(features, options);
  const auto g = grid_points(0.5, 0.5, 16.0, 33, 33);
  for (const Direction d : {Direction::kForward, Direction::kInverse}) {
    const auto a = mapped(coarse, g, d);
    const auto b = mapped(fine, g, d);
    double worst = 0.0;
    for (std::size_t i = 0; i < g.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
    EXPECT_LE(worst, 0.01);
  }
}

TEST(WarpProperties, GradientConstraintSetsTheJacobianAtTheFeature) {
  // Jacobian of f at each gradient feature by central differences equals (s1/s0)·e^{i(θ1−θ0)}, and is
  // conformal there (∂f/∂y = i·∂f/∂x).
  WarpOptions options;
  options.tolerance_px = 1e-10;
  testing::RandomFeatureSpec spec;
  spec.count = 12;
  spec.gradient_count = 4;
  spec.max_rotation_deg = 60.0;
  spec.seed = 21;
  for (const Prealign prealign : {Prealign::kSimilarity, Prealign::kNone}) {
    options.prealign = prealign;
    const WarpProblem problem(testing::random_features(spec, options), options);
    const double h = 1e-4;  // close features make the map's third derivatives large: keep h small
    for (const Feature& f : problem.features()) {
      if (!f.is_gradient()) continue;
      const auto v = mapped(problem, {f.source + h, f.source - h, f.source + Point(0, h), f.source - Point(0, h)},
                            Direction::kForward);
      const Point dfdx = (v[0] - v[1]) / (2 * h);
      const Point dfdy = (v[2] - v[3]) / (2 * h);
      const Point expected = std::polar(f.target_frame->scale / f.source_frame->scale,
                                        f.target_frame->angle_rad - f.source_frame->angle_rad);
      EXPECT_LE(std::abs(dfdx - expected), 1e-5 * std::abs(expected)) << f.id;
      EXPECT_LE(std::abs(dfdy - Point(0, 1) * expected), 1e-5 * std::abs(expected)) << f.id;
    }
  }
}

TEST(WarpProperties, TwoFeaturesGiveTheExactSimilarity) {
  // Both velocity fields are the pair's similarity at every time, so the flow is the similarity taking
  // P1 → Q1 and P2 → Q2, computed here directly.
  const Point p1(100, 100), q1(150, 120), p2(300, 200), q2(260, 330);
  for (const Prealign prealign : {Prealign::kSimilarity, Prealign::kNone}) {
    WarpOptions o;
    o.prealign = prealign;
    o.tolerance_px = 1e-8;
    const WarpProblem problem({{"1", p1, q1}, {"2", p2, q2}}, o);
    const Point a = (q2 - q1) / (p2 - p1);
    const auto g = grid_points(-100.5, -50.5, 41.0, 15, 15);
    const auto out = mapped(problem, g, Direction::kForward);
    for (std::size_t i = 0; i < g.size(); ++i) EXPECT_LE(std::abs(out[i] - (q1 + a * (g[i] - p1))), 1e-6) << i;
  }
}

TEST(WarpProperties, OneFeatureIsATranslation) {
  WarpOptions o;
  o.prealign = Prealign::kNone;
  const WarpProblem problem({{"1", {40, 50}, {47.5, 38}}}, o);
  const auto g = grid_points(0, 0, 50, 8, 8);
  const auto out = mapped(problem, g, Direction::kForward);
  for (std::size_t i = 0; i < g.size(); ++i) EXPECT_LE(std::abs(out[i] - (g[i] + Point(7.5, -12))), 1e-9);
}

TEST(WarpProperties, OneGradientFeatureIsItsSimilarity) {
  // v = D + κ(p − F(t)) integrates to p(1) − Q = e^κ (p(0) − P): rotation φ and scale S about the feature.
  WarpOptions o;
  o.prealign = Prealign::kNone;
  o.tolerance_px = 1e-8;
  const Point p(200, 150), q(230, 140);
  const WarpProblem problem({{"g", p, q, Frame{0.2, 1.0}, Frame{0.9, 1.6}}}, o);
  const Point m = std::polar(1.6, 0.7);
  const auto g = grid_points(0, 0, 40, 10, 10);
  const auto out = mapped(problem, g, Direction::kForward);
  for (std::size_t i = 0; i < g.size(); ++i) EXPECT_LE(std::abs(out[i] - (q + m * (g[i] - p))), 1e-6) << i;
}

// A crowded, rotating deformation: an inner ring of features turned by 120° inside a fixed outer ring. The
// thin-plate spline folds on it; the warp must not, for any α.
std::vector<Feature> swirl_features() {
  std::vector<Feature> f;
  const Point centre(256, 256);
  for (int k = 0; k < 6; ++k) {
    const Point r = std::polar(80.0, 2 * std::numbers::pi * k / 6);
    f.push_back(
        {"inner" + std::to_string(k), centre + r, centre + r * std::polar(1.0, 120.0 * std::numbers::pi / 180)});
  }
  for (int k = 0; k < 12; ++k) {
    const Point r = std::polar(140.0, 2 * std::numbers::pi * (k + 0.5) / 12);
    f.push_back({"outer" + std::to_string(k), centre + r, centre + r});
  }
  return f;
}

TEST(WarpProperties, FoldoverFreeWhereAThinPlateSplineFolds) {
  const auto features = swirl_features();
  const auto g = grid_points(0.5, 0.5, 8.0, 64, 64);

  std::vector<Point> src;
  std::vector<Point> dst;
  for (const Feature& f : features) {
    src.push_back(f.source);
    dst.push_back(f.target);
  }
  const ThinPlateSpline tps(src, dst);
  // The spline interpolates the features...
  for (std::size_t i = 0; i < src.size(); ++i) ASSERT_LE(std::abs(tps(src[i]) - dst[i]), 1e-6);
  // ...but folds.
  const JacobianStats tps_stats = summarize_determinants(jacobian_determinants(
      [&](std::vector<Point>& p) {
        for (Point& q : p) q = tps(q);
      },
      g, 1e-3));
  EXPECT_GT(tps_stats.nonpositive, 100u);
  EXPECT_LT(tps_stats.min_det, -0.5);

  CpuBackend cpu;
  for (const double alpha : {1.5, 2.0, 3.0}) {
    WarpOptions o;
    o.alpha = alpha;
    o.prealign = Prealign::kNone;
    const WarpProblem problem(features, o);
    for (const Direction d : {Direction::kForward, Direction::kInverse}) {
      const JacobianStats s = summarize_determinants(warp_jacobian_determinants(cpu, problem, g, d));
      EXPECT_EQ(s.nonpositive, 0u) << "alpha " << alpha;
      EXPECT_GT(s.min_det, 0.0) << "alpha " << alpha;
      EXPECT_EQ(s.samples, g.size());
    }
    EXPECT_LE(constraint_residuals(cpu, problem).max, 0.05);
  }
}

TEST(WarpProperties, FoldoverFreeOnLargeRandomDeformations) {
  CpuBackend cpu;
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    WarpOptions o;
    testing::RandomFeatureSpec spec;
    spec.count = 30;
    spec.gradient_count = 5;
    spec.max_displacement = 120.0;
    spec.max_rotation_deg = 90.0;
    spec.max_log_scale = 0.7;
    spec.seed = seed;
    const WarpProblem problem(testing::random_features(spec, well_separated(o)), o);
    const auto g = grid_points(0.5, 0.5, 512.0 / 40, 40, 40);
    const JacobianStats s = summarize_determinants(warp_jacobian_determinants(cpu, problem, g, Direction::kInverse));
    EXPECT_EQ(s.nonpositive, 0u) << "seed " << seed << " min det " << s.min_det;
  }
}

// warp_jacobians runs many points in parts of round-robin blocks: each point's Jacobian is the one a single call on
// all the points gives (to far below the differences between neighbours, 4.8 px apart), in the points' order, and
// the progress rises monotonically through every part to 1.
TEST(WarpProperties, JacobiansInPartsAreThoseOfOneCallInOrderWithProgress) {
  CpuBackend cpu;
  WarpOptions o;
  testing::RandomFeatureSpec spec;
  spec.count = 8;
  spec.gradient_count = 1;
  spec.max_displacement = 30.0;
  spec.seed = 5;
  const WarpProblem problem(testing::random_features(spec, well_separated(o)), o);
  const auto g = grid_points(0.5, 0.5, 512.0 / 107, 107, 101);  // 10807 points: 43 blocks, the last one short
  std::vector<double> progress;
  RunControl control;
  control.progress = [&progress](double f) { progress.push_back(f); };
  const std::vector<FlowJacobian> parts = warp_jacobians(cpu, problem, g, Direction::kInverse, control);
  WarpOptions tight_options = o;
  tight_options.tolerance_px = kJacobianTolerancePx;
  const WarpProblem tight(problem.features(), tight_options);
  std::vector<Point> ends = g;
  std::vector<FlowJacobian> whole(g.size());
  map_points_with_jacobian(cpu, tight, ends, whole, Direction::kInverse, {});
  ASSERT_EQ(parts.size(), g.size());
  for (std::size_t i = 0; i < g.size(); ++i) {
    ASSERT_LT(std::abs(parts[i].dx - whole[i].dx) + std::abs(parts[i].dy - whole[i].dy), 1e-6) << "point " << i;
  }
  const std::size_t blocks = (g.size() + kJacobianBlockPoints - 1) / kJacobianBlockPoints;
  const std::size_t expected_parts = std::min(kJacobianParts, blocks / kJacobianMinBlocksPerPart);
  ASSERT_GE(expected_parts, 2u);
  std::size_t part_ends = 0;  // the fractions k / parts reached
  for (std::size_t k = 1; k < progress.size(); ++k) EXPECT_GE(progress[k], progress[k - 1]) << "call " << k;
  for (const double f : progress) {
    const double k = f * static_cast<double>(expected_parts);
    if (std::abs(k - std::round(k)) < 1e-12 && k >= 1.0) ++part_ends;
  }
  EXPECT_GE(part_ends, expected_parts);
  ASSERT_FALSE(progress.empty());
  EXPECT_EQ(progress.back(), 1.0);
}

}  // namespace
}  // namespace texwarp
