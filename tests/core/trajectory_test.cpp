// Planned trajectories (issue 13): feature sets whose straight trajectories collide are warped, exactly and
// without folds, along piecewise linear trajectories whose separation the tests measure independently (dense
// sampling in time); sets that pass straight keep one segment; the planner on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "crossing_features.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/dormand_prince.hpp"
#include "texwarp/core/trajectory_planner.hpp"
#include "texwarp/core/trajectory_segment.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {
namespace {

constexpr double kBoundPx = 1e-3;
constexpr double kSize = 128.0;

// The smallest distance between any two features at 400 evenly spaced times of every segment (positions linear
// in time between waypoints): an independent estimate of the plan's separation.
double sampled_min_separation(const std::vector<std::vector<Point>>& w) {
  double best = std::numeric_limits<double>::infinity();
  constexpr int kSamples = 400;
  for (std::size_t k = 0; k + 1 < w.size(); ++k) {
    for (int s = 0; s <= kSamples; ++s) {
      const double t = static_cast<double>(s) / kSamples;
      for (std::size_t i = 0; i < w[k].size(); ++i) {
        const Point pi = w[k][i] + t * (w[k + 1][i] - w[k][i]);
        for (std::size_t j = i + 1; j < w[k].size(); ++j) {
          best = std::min(best, std::abs(pi - (w[k][j] + t * (w[k + 1][j] - w[k][j]))));
        }
      }
    }
  }
  return best;
}

// The sources and targets of 40 random crossing features (swaps, and turned clusters for even seeds) in 512².
std::pair<std::vector<Point>, std::vector<Point>> random_crossing_points(std::uint32_t seed) {
  std::pair<std::vector<Point>, std::vector<Point>> points;
  for (const Feature& x : testing::random_crossing_features(40, 512.0, seed, seed % 2 == 0)) {
    points.first.push_back(x.source);
    points.second.push_back(x.target);
  }
  return points;
}

class CrossingSets : public ::testing::TestWithParam<testing::CrossingSet> {};

TEST_P(CrossingSets, WarpExactlyAndWithoutFoldsAlongSeparatedTrajectories) {
  const testing::CrossingSet& set = GetParam();
  const auto& features = set.features;
  // Refused before planning: the straight trajectories (after pre-alignment) come closer than the minimum.
  const WarpProblem problem(features, set.options);
  const TrajectoryPlan& plan = problem.trajectory_plan();
  EXPECT_NE(plan.method, TrajectoryMethod::kStraight);
  ASSERT_GE(problem.segments().size(), 2u);
  ASSERT_EQ(plan.waypoints.size(), problem.segments().size() + 1);
  ASSERT_EQ(plan.knots.size(), problem.segments().size() + 1);
  EXPECT_EQ(plan.knots.front(), 0.0);
  EXPECT_EQ(plan.knots.back(), 1.0);
  for (std::size_t k = 0; k + 1 < plan.knots.size(); ++k) EXPECT_LT(plan.knots[k], plan.knots[k + 1]);
  for (std::size_t i = 0; i < features.size(); ++i) {
    EXPECT_EQ(plan.waypoints.front()[i], problem.prealignment()(features[i].source));
    EXPECT_EQ(plan.waypoints.back()[i], features[i].target);
  }
  // Every segment's pairwise separation, sampled densely, keeps the minimum and the reported exact value.
  const double sampled = sampled_min_separation(plan.waypoints);
  EXPECT_GE(sampled, set.options.min_separation_px) << set.name;
  EXPECT_GE(sampled, plan.min_separation_px - 1e-9);
  EXPECT_LE(sampled, plan.min_separation_px * 1.01 + 1e-6);  // the exact minimum is what sampling approaches
  EXPECT_NEAR(problem.closest_approach().distance_px, plan.min_separation_px, 1e-12);

  CpuBackend cpu;
  // Interpolation, forward and inverse.
  std::vector<Point> sources;
  std::vector<Point> targets;
  for (const Feature& f : features) {
    sources.push_back(f.source);
    targets.push_back(f.target);
  }
  std::vector<Point> forward = sources;
  map_points(cpu, problem, forward, Direction::kForward);
  std::vector<Point> inverse = targets;
  map_points(cpu, problem, inverse, Direction::kInverse);
  for (std::size_t i = 0; i < features.size(); ++i) {
    EXPECT_LE(std::abs(forward[i] - targets[i]), kBoundPx) << set.name << " feature " << i;
    EXPECT_LE(std::abs(inverse[i] - sources[i]), kBoundPx) << set.name << " feature " << i;
  }
  // Round trip at random points.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, kSize);
  std::vector<Point> random(12);
  for (Point& p : random) p = Point(u(rng), u(rng));
  std::vector<Point> round = random;
  map_points(cpu, problem, round, Direction::kForward);
  map_points(cpu, problem, round, Direction::kInverse);
  for (std::size_t i = 0; i < random.size(); ++i) EXPECT_LE(std::abs(round[i] - random[i]), kBoundPx) << set.name;

  // det J > 0 on a grid (the variational equation, chained over the segments), and the chained Jacobian equals
  // central differences of the map.
  std::vector<Point> grid;
  for (int y = 0; y < 6; ++y) {
    for (int x = 0; x < 6; ++x) grid.emplace_back(8.0 + 22.0 * x, 8.0 + 22.0 * y);
  }
  std::vector<Point> ends = grid;
  std::vector<FlowJacobian> jacobians(grid.size());
  map_points_with_jacobian(cpu, problem, ends, jacobians, Direction::kInverse);
  for (std::size_t i = 0; i < grid.size(); ++i) EXPECT_GT(jacobians[i].det(), 0.0) << set.name << " at " << grid[i];
  constexpr double kStep = 1e-3;
  for (std::size_t i = 0; i < grid.size(); i += 7) {
    std::vector<Point> q = {grid[i] + kStep, grid[i] - kStep, grid[i] + Point(0, kStep), grid[i] - Point(0, kStep)};
    map_points(cpu, problem, q, Direction::kInverse);
    const Point dx = (q[0] - q[1]) / (2 * kStep);
    const Point dy = (q[2] - q[3]) / (2 * kStep);
    const double scale = 1.0 + std::abs(jacobians[i].dx) + std::abs(jacobians[i].dy);
    EXPECT_LE(std::abs(dx - jacobians[i].dx), 0.02 * scale) << set.name << " at " << grid[i];
    EXPECT_LE(std::abs(dy - jacobians[i].dy), 0.02 * scale) << set.name << " at " << grid[i];
  }
}

TEST_P(CrossingSets, GradientFeaturesGetTheirWholeJacobianOverTheSegments) {
  const testing::CrossingSet& set = GetParam();
  WarpOptions options = set.options;
  options.tolerance_px = 1e-7;
  const WarpProblem problem(set.features, options);
  CpuBackend cpu;
  for (const Feature& f : set.features) {
    if (!f.is_gradient()) continue;
    std::vector<Point> p = {f.source};
    std::vector<FlowJacobian> j(1);
    map_points_with_jacobian(cpu, problem, p, j, Direction::kForward);
    // S·e^{iφ} (Eq. 4): a conformal Jacobian, its columns dx = S·e^{iφ}, dy = i·dx.
    const Point expected = std::polar(f.target_frame->scale / f.source_frame->scale,
                                      f.target_frame->angle_rad - f.source_frame->angle_rad);
    EXPECT_LE(std::abs(j[0].dx - expected), 1e-4) << set.name;
    EXPECT_LE(std::abs(j[0].dy - Point(0, 1) * expected), 1e-4) << set.name;
  }
}

INSTANTIATE_TEST_SUITE_P(RefusedBeforePlanning, CrossingSets,
                         ::testing::ValuesIn(testing::crossing_sets(kSize, false, 1e-5)),
                         [](const ::testing::TestParamInfo<testing::CrossingSet>& p) { return p.param.name; });

TEST(Trajectories, ADenseSetWithManyCrossingsInterpolatesWithoutFolds) {
  const auto sets = testing::crossing_sets(kSize, true, 1e-4);
  const testing::CrossingSet& set = sets.back();
  ASSERT_EQ(set.features.size(), 100u);
  const WarpProblem problem(set.features, set.options);
  EXPECT_NE(problem.trajectory_plan().method, TrajectoryMethod::kStraight);
  EXPECT_GE(sampled_min_separation(problem.trajectory_plan().waypoints), set.options.min_separation_px);
  CpuBackend cpu;
  std::vector<Point> forward;
  for (const Feature& f : set.features) forward.push_back(f.source);
  map_points(cpu, problem, forward, Direction::kForward);
  for (std::size_t i = 0; i < forward.size(); ++i) EXPECT_LE(std::abs(forward[i] - set.features[i].target), kBoundPx);
  std::vector<Point> grid = {{20, 20}, {64, 64}, {100, 30}, {30, 100}, {110, 110}};
  std::vector<FlowJacobian> j(grid.size());
  map_points_with_jacobian(cpu, problem, grid, j, Direction::kInverse);
  for (const FlowJacobian& x : j) EXPECT_GT(x.det(), 0.0);
}

TEST(Trajectories, SetsThatPassStraightKeepOneStraightSegment) {
  std::vector<Feature> f = {{"a", {10, 10}, {20, 15}}, {"b", {200, 50}, {190, 60}}, {"c", {100, 150}, {110, 140}}};
  const WarpProblem problem(f, {});
  const TrajectoryPlan& plan = problem.trajectory_plan();
  EXPECT_EQ(plan.method, TrajectoryMethod::kStraight);
  ASSERT_EQ(problem.segments().size(), 1u);
  EXPECT_EQ(plan.knots, (std::vector<double>{0.0, 1.0}));
  // The one segment is the paper's straight motion: start S(P), velocity Q − S(P).
  for (const PositionalTrajectory& t : problem.segments()[0].positional) {
    EXPECT_EQ(t.start, problem.prealignment()(f[t.feature].source));
    EXPECT_EQ(t.velocity, f[t.feature].target - problem.prealignment()(f[t.feature].source));
  }
}

TEST(Trajectories, SourcesCloserThanTheMinimumAreStillRefusedWithBothNamed) {
  // No trajectories can keep two sources apart that start 0.3 px apart.
  std::vector<Feature> f = {{"a", {10, 10}, {50, 10}}, {"b", {10.3, 10}, {10, 50}}, {"c", {80, 80}, {80, 80}}};
  WarpOptions o;
  o.prealign = Prealign::kNone;
  try {
    const WarpProblem problem(f, o);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("features[0] (\"a\") and features[1] (\"b\") come within 0.3 px"), std::string::npos) << msg;
  }
}

// The planner alone: random swaps and turned clusters, collinear sources (every projection direction but one
// spreads them), and a reversal of a tight row: every plan keeps the minimum, checked by sampling.
TEST(TrajectoryPlanner, KeepsTheMinimumOnHardSets) {
  std::vector<std::pair<std::vector<Point>, std::vector<Point>>> cases;
  for (std::uint32_t seed = 1; seed <= 6; ++seed) {
    cases.push_back(random_crossing_points(seed));
  }
  {
    std::vector<Point> s, q;
    for (int i = 0; i < 30; ++i) {
      s.emplace_back(100.0, 100.0 + 1.0 * i);  // a vertical row 1 px apart, reversed in place
      q.emplace_back(100.0, 100.0 + 1.0 * (29 - i));
    }
    cases.emplace_back(s, q);
  }
  for (const auto& [s, q] : cases) {
    const TrajectoryPlan plan = plan_trajectories(s, q, 0.5, 10.0);
    EXPECT_NE(plan.method, TrajectoryMethod::kStraight);  // without pre-alignment, swaps meet exactly
    EXPECT_GE(plan.min_separation_px, 0.5);
    EXPECT_NEAR(plan.min_separation_px, plan_min_separation(plan.waypoints), 0.0);
    EXPECT_GE(sampled_min_separation(plan.waypoints), 0.5);
    EXPECT_EQ(plan.waypoints.front(), s);
    EXPECT_EQ(plan.waypoints.back(), q);
  }
}

// The pair energy against an independent integration: ∫ |ΔD|² / |ΔF(s)|² ds per segment (composite Simpson in the
// segment's local time, fine enough to resolve a pass at 1 px), over the segment's duration τ.
double integrated_pair_energy(const std::vector<std::vector<Point>>& w, const std::vector<double>& knots) {
  double total = 0.0;
  constexpr int kIntervals = 200000;
  for (std::size_t k = 0; k + 1 < w.size(); ++k) {
    for (std::size_t i = 0; i < w[k].size(); ++i) {
      for (std::size_t j = i + 1; j < w[k].size(); ++j) {
        const Point a = w[k][j] - w[k][i];
        const Point delta = (w[k + 1][j] - w[k + 1][i]) - a;
        double sum = 0.0;
        for (int m = 0; m <= kIntervals; ++m) {
          const double weight = m == 0 || m == kIntervals ? 1.0 : (m % 2 == 1 ? 4.0 : 2.0);
          sum += weight * std::norm(delta) / std::norm(a + (static_cast<double>(m) / kIntervals) * delta);
        }
        total += sum / (3.0 * kIntervals) / (knots[k + 1] - knots[k]);
      }
    }
  }
  return total;
}

TEST(TrajectoryPlanner, ThePairEnergyIsTheIntegralOfTheSquaredPairRate) {
  const double far = std::numeric_limits<double>::infinity();
  // A pass 1 px apart (the pair turns by 169°), a head-on approach that stops short, a slight turn, three features
  // over two unequal segments.
  const std::vector<std::pair<std::vector<std::vector<Point>>, std::vector<double>>> plans = {
      {{{{0, 0}, {-10, 1}}, {{0, 0}, {10, 1}}}, {0.0, 1.0}},
      {{{{0, 0}, {30, 0}}, {{0, 0}, {2, 0}}}, {0.0, 1.0}},
      {{{{0, 0}, {20, 0}}, {{1, 1}, {19, 6}}}, {0.0, 1.0}},
      {{{{0, 0}, {10, 0}, {5, 9}}, {{3, 2}, {8, -4}, {5, 1}}, {{7, 0}, {0, 0}, {2, 8}}}, {0.0, 0.3, 1.0}},
  };
  for (const auto& [w, knots] : plans) {
    const double expected = integrated_pair_energy(w, knots);
    EXPECT_NEAR(plan_energy(w, knots, far), expected, 1e-8 * expected);
  }
  // A pair that meets has infinite energy.
  EXPECT_EQ(plan_energy({{{0, 0}, {-10, 0}}, {{0, 0}, {10, 0}}}, {0.0, 1.0}, far), far);
}

// The energy's gradient against central differences of the energy itself (step 1e-5 px), in every coordinate of
// every waypoint: a close pass, a slight turn and the three features over two unequal segments.
TEST(TrajectoryPlanner, ThePairEnergysGradientIsItsDerivative) {
  const double far = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<std::vector<std::vector<Point>>, std::vector<double>>> plans = {
      {{{{0, 0}, {-10, 1}}, {{0, 0}, {10, 1}}}, {0.0, 1.0}},
      {{{{0, 0}, {20, 0}}, {{1, 1}, {19, 6}}}, {0.0, 1.0}},
      {{{{0, 0}, {10, 0}, {5, 9}}, {{3, 2}, {8, -4}, {5, 1}}, {{7, 0}, {0, 0}, {2, 8}}}, {0.0, 0.3, 1.0}},
  };
  constexpr double kStep = 1e-5;
  for (const auto& [w, knots] : plans) {
    std::vector<std::vector<Point>> gradient;
    const double energy = plan_energy(w, knots, far, &gradient);
    EXPECT_EQ(energy, plan_energy(w, knots, far));
    ASSERT_EQ(gradient.size(), w.size());
    for (std::size_t k = 0; k < w.size(); ++k) {
      ASSERT_EQ(gradient[k].size(), w[k].size());
      for (std::size_t i = 0; i < w[k].size(); ++i) {
        for (const Point axis : {Point(1.0, 0.0), Point(0.0, 1.0)}) {
          auto plus = w;
          auto minus = w;
          plus[k][i] += kStep * axis;
          minus[k][i] -= kStep * axis;
          const double numeric = (plan_energy(plus, knots, far) - plan_energy(minus, knots, far)) / (2.0 * kStep);
          const double analytic = axis.real() != 0.0 ? gradient[k][i].real() : gradient[k][i].imag();
          EXPECT_NEAR(analytic, numeric, 1e-5 * std::max(1.0, std::abs(numeric)))
              << "waypoint " << k << ", feature " << i << ", axis " << axis;
        }
      }
    }
  }
}

// Straight lines that keep the minimum but pass close get intermediate configurations that lower the energy;
// crossing sets' plans are lowered too; every lowered plan keeps the minimum (sampled) and its ends.
TEST(TrajectoryPlanner, LowersThePairEnergyKeepingTheMinimum) {
  {
    // Two features passing 1 px apart, 20 px spacing: a near miss for straight lines.
    const std::vector<Point> s = {{0, 0}, {20, 1}};
    const std::vector<Point> q = {{20, 0}, {0, 1}};
    const TrajectoryPlan as_found = plan_trajectories(s, q, 0.5, 20.0, false, true);
    EXPECT_EQ(as_found.method, TrajectoryMethod::kStraight);
    EXPECT_FALSE(as_found.energy_lowered());
    EXPECT_EQ(plan_trajectories(s, q, 0.5, 20.0).segments(), 1u);  // near misses kept unless asked
    const TrajectoryPlan plan = plan_trajectories(s, q, 0.5, 20.0, true, true);
    ASSERT_TRUE(plan.energy_lowered());
    EXPECT_FALSE(plan.straight_collides);
    EXPECT_EQ(plan.segments(), 4u);
    EXPECT_NEAR(plan.energy_before, plan_energy(as_found.waypoints, as_found.knots, 80.0), 1e-9 * plan.energy_before);
    EXPECT_NEAR(plan.energy, plan_energy(plan.waypoints, plan.knots, 80.0), 1e-9 * plan.energy);
    EXPECT_LT(plan.energy, 0.5 * plan.energy_before);
    EXPECT_GT(plan.min_separation_px, 2.0);  // they pass wider apart
    EXPECT_EQ(plan.waypoints.front(), s);
    EXPECT_EQ(plan.waypoints.back(), q);
  }
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    const auto [s, q] = random_crossing_points(seed);
    const TrajectoryPlan as_found = plan_trajectories(s, q, 0.5, 10.0, false);
    const TrajectoryPlan plan = plan_trajectories(s, q, 0.5, 10.0);
    EXPECT_TRUE(plan.straight_collides);
    EXPECT_TRUE(plan.energy_measured);
    // Lowering a plan found without it is what the planner returns with it (WarpProblem plans, then lowers).
    const TrajectoryPlan later = lower_trajectory_energy(as_found, 0.5, 10.0, false);
    EXPECT_EQ(later.waypoints, plan.waypoints);
    EXPECT_EQ(later.energy, plan.energy);
    EXPECT_TRUE(later.straight_collides);
    EXPECT_EQ(plan.method, as_found.method);
    EXPECT_EQ(plan.knots, as_found.knots);
    if (plan.energy_lowered()) {
      EXPECT_LT(plan.energy, plan.energy_before);
      EXPECT_NEAR(plan.energy_before, plan_energy(as_found.waypoints, as_found.knots, 40.0), 1e-9 * plan.energy_before);
    }
    EXPECT_GE(sampled_min_separation(plan.waypoints), 0.5);
    EXPECT_EQ(plan.waypoints.front(), s);
    EXPECT_EQ(plan.waypoints.back(), q);
  }
}

TEST(Trajectories, WithoutLoweringANearMissKeepsItsStraightLines) {
  std::vector<Feature> f = {{"a", {0, 0}, {20, 0}}, {"b", {20, 1}, {0, 1}}, {"c", {100, 100}, {100, 100}}};
  WarpOptions o;
  o.prealign = Prealign::kNone;
  EXPECT_EQ(WarpProblem(f, o).trajectory_plan().segments(), 1u);  // an image warp's default
  o.widen_near_misses = true;                                     // a mesh mapping's
  EXPECT_EQ(WarpProblem(f, o).trajectory_plan().segments(), 4u);
  o.lower_energy = false;
  const WarpProblem problem(f, o);
  EXPECT_EQ(problem.trajectory_plan().method, TrajectoryMethod::kStraight);
  EXPECT_EQ(problem.trajectory_plan().segments(), 1u);
}

// A segment's time scale, by hand: a feature moving 10 px past a still one 3 px off its line comes closest at
// t = 0.5, 3 px apart at a relative speed of 10 px per unit time (τ = 0.3); a gradient feature turning by 2 rad
// over the segment changes within 1/2; features that move together, or not at all, never change the field's time.
TEST(TrajectorySegment, TheTimeScaleIsTheShortestPassOrTurn) {
  const std::vector<Point> from = {Point(0, 0), Point(5, 3), Point(200, 200), Point(400, 50)};
  const std::vector<Point> to = {Point(10, 0), Point(5, 3), Point(200, 200), Point(400, 50)};
  const std::vector<Point> still(4, Point(0, 0));
  const std::vector<bool> positional(4, false);
  EXPECT_DOUBLE_EQ(make_segment(from, to, still, positional, 0.0, 1.0, 1.0).time_scale, 0.3);
  EXPECT_DOUBLE_EQ(dormand_prince::first_step(0.3), dormand_prince::kMinFirstStep);

  std::vector<Point> rates = still;
  rates[2] = Point(0.0, 2.0);  // feature 2 gradient, turning by 2 rad
  std::vector<bool> gradient = positional;
  gradient[2] = true;
  const std::vector<Point> together = {Point(10, 0), Point(15, 3), Point(210, 200), Point(410, 50)};
  EXPECT_DOUBLE_EQ(make_segment(from, together, rates, gradient, 0.0, 1.0, 1.0).time_scale, 0.5);
  EXPECT_DOUBLE_EQ(make_segment(from, together, rates, gradient, 0.0, 0.5, 1.0).time_scale, 1.0);  // half the turn
  EXPECT_EQ(dormand_prince::first_step(1.0), dormand_prince::kMinFirstStep);
  EXPECT_EQ(dormand_prince::first_step(dormand_prince::kWholeSegmentTimeScale), 1.0);

  const TrajectorySegment rigid = make_segment(from, together, still, positional, 0.0, 1.0, 1.0);
  EXPECT_EQ(rigid.time_scale, std::numeric_limits<double>::infinity());
  EXPECT_EQ(dormand_prince::first_step(rigid.time_scale), 1.0);
  EXPECT_EQ(make_segment(from, from, still, positional, 0.0, 1.0, 1.0).time_scale,
            std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace texwarp
