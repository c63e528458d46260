// Tests of the pathline integrator (Eq. 1) where the field changes fast: points near a close pass of two feature
// trajectories, at the default tolerance, against a run at a tolerance far below it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "crossing_features.hpp"
#include "point_compare.hpp"
#include "random_features.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/dormand_prince.hpp"
#include "texwarp/core/pathline.hpp"
#include "texwarp/core/velocity_field.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {
namespace {

using testing::max_difference;

constexpr Point kPass(200.0, 150.0);

// Two features that swap places across kPass, passing 1 px apart at t = 0.5 (relative speed 24 px per unit
// time: the pair's field turns by half a turn within ~0.04 of t), among twelve features on a ring around them
// that move a few pixels each.
std::vector<Feature> close_pass_features() {
  std::vector<Feature> features;
  features.push_back({"a", kPass + Point(-6.0, 0.5), kPass + Point(6.0, 0.5)});
  features.push_back({"b", kPass + Point(6.0, -0.5), kPass + Point(-6.0, -0.5)});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int k = 0; k < 12; ++k) {
    const Point p = kPass + std::polar(40.0 + 10.0 * unit(rng), 2.0 * 3.14159265358979 * k / 12.0);
    features.push_back({"ring" + std::to_string(k), p, p + 4.0 * Point(unit(rng), unit(rng))});
  }
  return features;
}

// Points on rings of 2 to 48 px around the pass: inside the rings the pair (a, b) outweighs the others, and its
// field turns them by about half a turn around kPass within ~0.1 of t = 0.5.
std::vector<Point> points_near_the_pass() {
  std::vector<Point> points;
  for (const double radius : {2.0, 4.0, 8.0, 16.0, 32.0, 48.0}) {
    for (int k = 0; k < 16; ++k) points.push_back(kPass + std::polar(radius, (k + 0.5) * 3.14159265358979 / 8.0));
  }
  return points;
}

// Each point on its own, so that the step sequence is the point's own: in a batch, a point closer to the pass
// keeps the steps short for all.
void integrate_one_by_one(const VelocityField& field, std::vector<Point>& points, Direction direction,
                          double tolerance_px) {
  for (Point& p : points) integrate_pathlines(field, std::span<Point>(&p, 1), direction, tolerance_px);
}

void integrate_one_by_one(const VelocityField& field, std::vector<Point>& points, std::vector<FlowJacobian>& jacobians,
                          Direction direction, double tolerance_px) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    integrate_pathlines(field, std::span<Point>(&points[i], 1), std::span<FlowJacobian>(&jacobians[i], 1), direction,
                        tolerance_px);
  }
}

class ClosePass : public ::testing::Test {
 protected:
  ClosePass() : problem_(close_pass_features(), WarpOptions{}), field_(problem_) {}

  WarpProblem problem_;
  VelocityField field_;
};

TEST_F(ClosePass, TheSetHasTheNearCollisionItIsMeantToHave) {
  const ClosestApproach& ca = problem_.closest_approach();
  EXPECT_EQ(ca.first, 0u);
  EXPECT_EQ(ca.second, 1u);
  EXPECT_LT(ca.distance_px, 1.5);
  EXPECT_NEAR(ca.t, 0.5, 0.05);
  ASSERT_FALSE(problem_.near_collisions().empty());
}

TEST_F(ClosePass, PointsNearThePassMeetTheTolerance) {
  const double tolerance = problem_.tolerance_px();
  ASSERT_EQ(tolerance, 0.01);
  for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
    std::vector<Point> reference = points_near_the_pass();
    std::vector<Point> actual = reference;
    integrate_one_by_one(field_, reference, direction, 1e-7);
    integrate_one_by_one(field_, actual, direction, tolerance);
    const double error = max_difference(actual, reference);
    EXPECT_LE(error, tolerance) << (direction == Direction::kForward ? "forward" : "inverse");
    char text[32];
    std::snprintf(text, sizeof text, "%.3e", error);
    RecordProperty(direction == Direction::kForward ? "forward_max_error_px" : "inverse_max_error_px", text);
  }
}

TEST_F(ClosePass, WithTheVariationalEquationToo) {
  const double tolerance = problem_.tolerance_px();
  std::vector<Point> reference = points_near_the_pass();
  std::vector<Point> actual = reference;
  std::vector<FlowJacobian> reference_jacobians(reference.size());
  std::vector<FlowJacobian> jacobians(reference.size());
  integrate_one_by_one(field_, reference, reference_jacobians, Direction::kInverse, 1e-7);
  integrate_one_by_one(field_, actual, jacobians, Direction::kInverse, tolerance);
  EXPECT_LE(max_difference(actual, reference), tolerance);
  double worst = 0.0;
  for (std::size_t i = 0; i < jacobians.size(); ++i) {
    const FlowJacobian& j = jacobians[i];
    const FlowJacobian& r = reference_jacobians[i];
    const double scale = std::max(std::abs(r.dx), std::abs(r.dy));
    worst = std::max({worst, std::abs(j.dx - r.dx) / scale, std::abs(j.dy - r.dy) / scale});
    EXPECT_GT(j.det(), 0.0) << "point " << i;
  }
  EXPECT_LE(worst, 0.01);
  char text[32];
  std::snprintf(text, sizeof text, "%.3e", worst);
  RecordProperty("jacobian_max_relative_error", text);
}

// A field that changes slowly in time and space: 64 features on a grid over 512², each moved a few pixels by a
// smooth displacement, as a mesh's flattening moves neighbours together.
std::vector<Feature> slowly_changing_features() {
  std::vector<Feature> features;
  for (int row = 0; row < 8; ++row) {
    for (int column = 0; column < 8; ++column) {
      const Point p(32.0 + 64.0 * column, 32.0 + 64.0 * row);
      const Point move(6.0 * std::sin(p.imag() / 90.0), 5.0 * std::cos(p.real() / 110.0));
      features.push_back({"g" + std::to_string(8 * row + column), p, p + move});
    }
  }
  return features;
}

// Features that move with their neighbours: the first step is the whole segment, and where the error estimate allows
// it a batch of pathlines is one Dormand–Prince step (7 field evaluations; with a first step of 1/8 and growth capped
// at 5×, every pathline took at least three, 19 evaluations), its positions and Jacobians still within the tolerance
// of a run far below it.
TEST(StepControl, ASlowlyChangingFieldTakesOneStepWithinTheTolerance) {
  const WarpProblem problem(slowly_changing_features(), WarpOptions{});
  const VelocityField field(problem);
  ASSERT_TRUE(problem.near_collisions().empty());
  ASSERT_EQ(problem.segments().size(), 1u);
  ASSERT_GE(problem.segments()[0].time_scale, dormand_prince::kWholeSegmentTimeScale);
  std::vector<Point> start;
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) start.emplace_back(13.0 + 32.0 * x, 7.0 + 32.0 * y);
  }
  const double tolerance = problem.tolerance_px();
  for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
    std::vector<Point> reference = start;
    std::vector<FlowJacobian> reference_jacobians(start.size());
    integrate_one_by_one(field, reference, reference_jacobians, direction, 1e-9);
    std::vector<Point> actual = start;
    std::vector<FlowJacobian> jacobians(start.size());
    const IntegrationStats stats = integrate_pathlines(field, actual, jacobians, direction, tolerance);
    EXPECT_EQ(stats.steps, 1u);
    EXPECT_EQ(stats.rejected, 0u);
    EXPECT_EQ(stats.evaluations, 7u);
    const double error = max_difference(actual, reference);
    EXPECT_LE(error, tolerance);
    // The lattice's Hermite cells rest on one-step Jacobians too: within 1 % of the reference, as near a close pass.
    for (std::size_t i = 0; i < start.size(); ++i) {
      const FlowJacobian& j = jacobians[i];
      const FlowJacobian& r = reference_jacobians[i];
      const double scale = std::max(std::abs(r.dx), std::abs(r.dy));
      EXPECT_LE(std::max(std::abs(j.dx - r.dx), std::abs(j.dy - r.dy)) / scale, 0.01) << "point " << i;
    }
    char text[32];
    std::snprintf(text, sizeof text, "%.3e", error);
    RecordProperty(direction == Direction::kForward ? "forward_max_error_px" : "inverse_max_error_px", text);
  }
}

// Where trajectories cross (the planned sets of the OpenCL parity tests, and 100 dense ones), time scales are below
// kWholeSegmentTimeScale and the first step stays 1/8; points every 4 px over the whole 96² image meet the tolerance
// against a run far below it. A first step of the whole segment, whatever the trajectories, left errors of up to 2.3×
// the tolerance on the permuted grid (41×37 pixels): its stages missed where the field changes, and its error
// estimate with them.
// The permuted grids are pre-aligned by a similarity of scale 0.5, so that the inverse map's points leave the flow
// through a scaling by 2: integrated to the tolerance in the flow's space, permuted_grid_gradients missed it by 1.8×
// and 1.7× at 0.01 and 0.05 px where the points land (WarpProblem::pathline_tolerance_px).
TEST(StepControl, CrossingTrajectoriesMeetTheToleranceEverywhere) {
  CpuBackend cpu;
  std::vector<Point> start;
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 24; ++x) start.emplace_back(4.0 * x + 1.5, 4.0 * y + 1.5);
  }
  for (const testing::CrossingSet& set : testing::crossing_sets(96.0, true, 1e-3)) {
    WarpOptions options = set.options;
    options.tolerance_px = 1e-9;
    const WarpProblem tight(set.features, options);
    for (const TrajectorySegment& segment : tight.segments()) {
      EXPECT_EQ(dormand_prince::first_step(segment.time_scale), dormand_prince::kMinFirstStep) << set.name;
    }
    std::vector<Point> truth = start;
    map_points(cpu, tight, truth, Direction::kInverse);
    for (const double tolerance : {1e-3, 1e-2, 5e-2}) {
      options.tolerance_px = tolerance;
      const WarpProblem problem(set.features, options);
      ASSERT_EQ(problem.trajectory_plan().waypoints, tight.trajectory_plan().waypoints) << set.name;
      std::vector<Point> actual = start;
      map_points(cpu, problem, actual, Direction::kInverse);
      EXPECT_LE(max_difference(actual, truth), tolerance) << set.name << " at " << tolerance << " px";
    }
  }
}

// A pathline that starts on a feature moves with it at constant velocity: its position error estimate is zero
// and, alone in a batch, it took three steps whatever the tolerance, its Jacobian off by up to 5.6e-3 at 1e-9.
// The Jacobian's own error estimate now steers the step too: compared with central differences of pathlines
// beside it (each in its own batch, so that their own errors steer their steps).
TEST(VariationalEquation, AccurateOnAFeatureTrajectoryAlone) {
  testing::RandomFeatureSpec spec;
  spec.count = 30;
  spec.gradient_count = 4;
  spec.seed = 5;
  const std::vector<Feature> features = testing::random_features(spec, {});
  const WarpProblem problem(features, {});
  const VelocityField field(problem);
  const double h = 1e-3;
  for (const Feature& f : problem.features()) {
    const Point start = problem.prealignment()(f.source);
    Point end = start;
    FlowJacobian j;
    integrate_pathlines(field, std::span<Point>(&end, 1), std::span<FlowJacobian>(&j, 1), Direction::kForward, 1e-9);
    std::vector<Point> probes = {start + Point(h, 0), start - Point(h, 0), start + Point(0, h), start - Point(0, h)};
    integrate_one_by_one(field, probes, Direction::kForward, 1e-11);
    const Point dx = (probes[0] - probes[1]) / (2 * h);
    const Point dy = (probes[2] - probes[3]) / (2 * h);
    const double scale = std::max(std::abs(dx), std::abs(dy));
    EXPECT_LE(std::max(std::abs(j.dx - dx), std::abs(j.dy - dy)) / scale, 1e-5) << f.id;
  }
}

}  // namespace
}  // namespace texwarp
