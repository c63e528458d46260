// Tests of feature validation and preparation: every documented error, closest approaches, pre-alignment of
// gradient frames, the degenerate sets of DESIGN.md §1.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "crossing_features.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

// Message of the InputError that constructing the problem throws ("" if it is accepted).
std::string rejection(const std::vector<Feature>& features, const WarpOptions& options = {}) {
  try {
    WarpProblem problem(features, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::vector<Feature> two_features() { return {{"a", {10, 10}, {20, 15}}, {"b", {200, 50}, {190, 60}}}; }

TEST(WarpProblem, RejectsAlphaOutOfRange) {
  for (const double alpha : {0.0, -1.0, 8.5, std::numeric_limits<double>::quiet_NaN()}) {
    WarpOptions o;
    o.alpha = alpha;
    EXPECT_NE(rejection(two_features(), o).find("$.alpha: alpha must be in (0, 8]"), std::string::npos) << alpha;
  }
}

TEST(WarpProblem, RejectsBadTolerance) {
  WarpOptions o;
  o.tolerance_px = 0.0;
  EXPECT_NE(rejection(two_features(), o).find("$.tolerance_px"), std::string::npos);
  o.tolerance_px = std::numeric_limits<double>::infinity();
  EXPECT_NE(rejection(two_features(), o).find("$.tolerance_px"), std::string::npos);
}

// with_tolerance copies the plan instead of planning again: it must be the problem a fresh construction with that
// tolerance gives, trajectories, pre-alignment and pathlines alike (planned sets, K > 1, gradient features among them).
TEST(WarpProblem, WithToleranceIsTheProblemBuiltWithThatTolerance) {
  CpuBackend cpu;
  std::size_t planned = 0;
  for (const testing::CrossingSet& set : testing::crossing_sets(128.0, false, 0.01)) {
    const WarpProblem original(set.features, set.options);
    const WarpProblem copied = original.with_tolerance(0.002);
    WarpOptions tighter = set.options;
    tighter.tolerance_px = 0.002;
    const WarpProblem fresh(set.features, tighter);
    EXPECT_EQ(original.tolerance_px(), set.options.tolerance_px) << set.name;
    EXPECT_EQ(copied.tolerance_px(), 0.002) << set.name;
    EXPECT_EQ(copied.prealignment().a, fresh.prealignment().a) << set.name;
    EXPECT_EQ(copied.prealignment().b, fresh.prealignment().b) << set.name;
    EXPECT_EQ(copied.trajectory_plan().knots, fresh.trajectory_plan().knots) << set.name;
    EXPECT_EQ(copied.trajectory_plan().waypoints, fresh.trajectory_plan().waypoints) << set.name;
    ASSERT_EQ(copied.segments().size(), fresh.segments().size()) << set.name;
    planned += copied.segments().size() > 1 ? 1 : 0;
    std::vector<Point> a;
    a.reserve(64);
    for (int k = 0; k < 64; ++k) a.emplace_back(4.0 + 1.9 * k, 120.0 - 1.7 * k);
    std::vector<Point> b = a;
    map_points(cpu, copied, a, Direction::kInverse, {});
    map_points(cpu, fresh, b, Direction::kInverse, {});
    EXPECT_EQ(a, b) << set.name;  // bit for bit: the same field, steps and tolerance
  }
  EXPECT_GT(planned, 0u);
}

TEST(WarpProblem, WithToleranceRejectsWhatTheConstructorRejects) {
  const WarpProblem problem(two_features(), {});
  for (const double tolerance : {0.0, -0.5, std::numeric_limits<double>::quiet_NaN()}) {
    try {
      (void)problem.with_tolerance(tolerance);
      ADD_FAILURE() << tolerance << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("$.tolerance_px"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(problem.tolerance_px(), WarpOptions{}.tolerance_px);
}

TEST(WarpProblem, RejectsNonFiniteCoordinates) {
  auto f = two_features();
  f[1].source = Point(std::numeric_limits<double>::quiet_NaN(), 1.0);
  EXPECT_EQ(rejection(f), "$.features[1]: feature \"b\": source is not a finite point");
  f = two_features();
  f[0].target = Point(1.0, std::numeric_limits<double>::infinity());
  EXPECT_EQ(rejection(f), "$.features[0]: feature \"a\": target is not a finite point");
}

TEST(WarpProblem, RejectsDuplicatePositions) {
  auto f = two_features();
  f.push_back({"", {10, 10}, {300, 300}});
  EXPECT_EQ(rejection(f), "$.features[2]: duplicate source position (10, 10): features[0] (\"a\") has the same one");
  f.back() = {"c", {300, 300}, {190, 60}};
  EXPECT_EQ(rejection(f),
            "$.features[2]: feature \"c\": duplicate target position (190, 60): features[1] (\"b\") has the same one");
}

TEST(WarpProblem, RejectsBadFrames) {
  auto f = two_features();
  f[0].source_frame = Frame{0.0, 1.0};
  EXPECT_NE(rejection(f).find("needs both a source frame and a target frame"), std::string::npos);
  f[0].target_frame = Frame{0.0, -2.0};
  EXPECT_NE(rejection(f).find("target_frame scale must be a finite number > 0"), std::string::npos);
}

TEST(WarpProblem, CollidingStraightTrajectoriesArePlannedAroundNotRefused) {
  // Two features swapping places meet half way, at t = 0.5: refused before trajectories were planned.
  std::vector<Feature> f = {{"left", {100, 100}, {300, 100}},
                            {"right", {300, 100}, {100, 100}},
                            {"still", {200, 400}, {200, 400}}};
  WarpOptions o;
  o.prealign = Prealign::kNone;
  EXPECT_EQ(rejection(f, o), "");
  const WarpProblem problem(f, o);
  EXPECT_NE(problem.trajectory_plan().method, TrajectoryMethod::kStraight);
  EXPECT_GE(problem.segments().size(), 2u);
  EXPECT_GE(problem.closest_approach().distance_px, o.min_separation_px);
}

TEST(WarpProblem, CollisionDistanceIsTheExactClosestApproach) {
  // Crossing paths: a moves right along y = 0, b moves up along x = 5 and passes 0.3 px away at t = 0.5.
  std::vector<Feature> f = {{"a", {0, 0}, {10, 0}}, {"b", {5, -5.3}, {5, 4.7}}, {"c", {50, 50}, {50, 50}}};
  WarpOptions o;
  o.prealign = Prealign::kNone;
  // Relative position r(t) = (5 − 10t, −5.3 + 10t); |r|² minimal at t = 0.515, distance 0.3/√2: below the
  // default minimum of 0.5 px, so the trajectories are planned around it; above 0.2 px they stay straight.
  EXPECT_NE(WarpProblem(f, o).trajectory_plan().method, TrajectoryMethod::kStraight);
  o.min_separation_px = 0.2;
  const WarpProblem ok(f, o);
  EXPECT_EQ(ok.trajectory_plan().method, TrajectoryMethod::kStraight);
  EXPECT_NEAR(ok.closest_approach().distance_px, 0.3 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(ok.closest_approach().t, 0.515, 1e-12);
  // Asked to (as mesh mappings do), a pass this narrow against the features' spacing is widened by lowering the pair
  // energy.
  o.widen_near_misses = true;
  const WarpProblem lowered(f, o);
  EXPECT_TRUE(lowered.trajectory_plan().energy_lowered());
  EXPECT_GT(lowered.closest_approach().distance_px, 1.0);
}

TEST(WarpProblem, NearCollisionsAreTheNarrowPassesWithTheirWindows) {
  // a and b pass 0.3/√2 px apart at t = 0.515 with relative speed 10√2 px per unit time: τ = 0.015. d and e pass
  // 1.5√2 px apart at t = 0.65 at the same speed: τ = 0.15, wide enough for the step control alone. Every other
  // pair is closest outside (0, 1) or moves in parallel.
  const std::vector<Feature> f = {{"a", {0, 0}, {10, 0}},
                                  {"b", {5, -5.3}, {5, 4.7}},
                                  {"c", {50, 50}, {50, 50}},
                                  {"d", {100, 0}, {110, 0}},
                                  {"e", {108, -5}, {108, 5}}};
  WarpOptions o;
  o.prealign = Prealign::kNone;
  o.min_separation_px = 0.2;
  const WarpProblem problem(f, o);
  ASSERT_EQ(problem.near_collisions().size(), 1u);
  EXPECT_NEAR(problem.near_collisions()[0].t, 0.515, 1e-12);
  EXPECT_NEAR(problem.near_collisions()[0].width, kNearCollisionWidthFactor * 0.015, 1e-12);
}

TEST(WarpProblem, NoFeaturesIsTheIdentityField) {
  const WarpProblem p({}, {});
  EXPECT_TRUE(p.field_is_zero());
  EXPECT_TRUE(p.positional().empty());
  EXPECT_TRUE(p.gradient().empty());
}

TEST(WarpProblem, ALonePositionalFeatureBecomesATranslation) {
  WarpOptions o;
  o.prealign = Prealign::kNone;
  const WarpProblem p({{"only", {10, 20}, {15, 27}}}, o);
  ASSERT_TRUE(p.positional().empty());
  ASSERT_EQ(p.gradient().size(), 1u);
  EXPECT_EQ(p.gradient()[0].rate, Point(0.0, 0.0));
  EXPECT_EQ(p.gradient()[0].velocity, Point(5.0, 7.0));
}

TEST(WarpProblem, GradientFramesFollowThePrealignment) {
  // Targets are the sources rotated by 90° and scaled by 2 about the origin: S is exactly that similarity;
  // a gradient feature asking for the same rotation and scale then needs no further change (κ = 0).
  const Point rot = std::polar(2.0, std::numbers::pi / 2);
  std::vector<Feature> f = {{"a", {10, 0}, rot * Point(10, 0)}, {"b", {0, 30}, rot * Point(0, 30)}};
  f.push_back({"g", {-20, -20}, rot * Point(-20, -20), Frame{0.1, 1.5}, Frame{0.1 + std::numbers::pi / 2, 3.0}});
  const WarpProblem p(f, {});
  EXPECT_NEAR(std::abs(p.prealignment().a - rot), 0.0, 1e-12);
  ASSERT_EQ(p.gradient().size(), 1u);
  EXPECT_NEAR(std::abs(p.gradient()[0].rate), 0.0, 1e-12);
  EXPECT_TRUE(p.field_is_zero() || std::abs(p.gradient()[0].velocity) < 1e-12);
}

// An inverse map's points leave the flow through S⁻¹, which multiplies their errors by 1/|a|: its pathlines are
// integrated to |a| times the tolerance where S shrinks, and to the tolerance itself where it keeps or grows the
// scale (no loosening). A forward map's points leave the flow as they are.
TEST(WarpProblem, PathlinesMeetTheToleranceWhereTheMapsPointsLand) {
  WarpOptions o;
  o.tolerance_px = 0.04;
  for (const double scale : {0.25, 0.5, 1.0, 3.0}) {
    const Point a = std::polar(scale, 0.7);
    std::vector<Feature> f = {{"a", {10, 20}, a * Point(10, 20)},
                              {"b", {200, 50}, a * Point(200, 50) + Point(3, 1)},
                              {"c", {90, 180}, a * Point(90, 180) - Point(2, 2)}};
    const WarpProblem p(f, o);
    const double shrink = std::abs(p.prealignment().a);
    ASSERT_NEAR(shrink, scale, 0.05 * scale);
    EXPECT_EQ(p.pathline_tolerance_px(Direction::kForward), 0.04) << scale;
    EXPECT_DOUBLE_EQ(p.pathline_tolerance_px(Direction::kInverse), 0.04 * std::min(1.0, shrink)) << scale;
    // Without a pre-alignment the flow's space is the texture's own.
    WarpOptions none = o;
    none.prealign = Prealign::kNone;
    EXPECT_EQ(WarpProblem(f, none).pathline_tolerance_px(Direction::kInverse), 0.04) << scale;
  }
}

TEST(WarpProblem, GradientRotationTakesTheShortWay) {
  WarpOptions o;
  o.prealign = Prealign::kNone;
  const double deg = std::numbers::pi / 180.0;
  const WarpProblem p({{"g", {0, 0}, {0, 0}, Frame{10 * deg, 1.0}, Frame{350 * deg, 1.0}}}, o);
  EXPECT_NEAR(p.gradient()[0].rate.imag(), -20 * deg, 1e-12);
}

}  // namespace
}  // namespace texwarp
