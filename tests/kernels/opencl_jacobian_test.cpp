// The OpenCL backend's flow Jacobians (the variational equation integrated in the pathline kernel) held to the
// CPU reference's variational equation, to central differences of the device's own map, and to closed forms:
// at and next to features, the identity, and a pure similarity.
#include <gtest/gtest.h>

#include <cmath>
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

// Frobenius norm of a Jacobian (its two complex columns).
double norm(const FlowJacobian& j) { return std::sqrt(std::norm(j.dx) + std::norm(j.dy)); }

// Largest ‖ΔJ‖ / ‖J_expected‖ over the points; +∞ when anything is not finite or the sizes differ.
double max_relative_difference(const std::vector<FlowJacobian>& actual, const std::vector<FlowJacobian>& expected) {
  if (actual.size() != expected.size()) return INFINITY;
  double worst = 0.0;
  for (std::size_t i = 0; i < actual.size(); ++i) {
    const double d =
        norm(FlowJacobian{actual[i].dx - expected[i].dx, actual[i].dy - expected[i].dy}) / norm(expected[i]);
    if (!std::isfinite(d)) return INFINITY;
    worst = std::max(worst, d);
  }
  return worst;
}

std::string scientific(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3e", x);
  return text;
}

// The same problem at another tolerance.
WarpProblem with_tolerance(const WarpProblem& problem, double tolerance_px) {
  WarpOptions options = problem.options();
  options.tolerance_px = tolerance_px;
  return WarpProblem(problem.features(), options);
}

// Where the flow W (pre-aligned frame) has its features at the start of the integration: F(0) forward, F(1)
// inverse, positional and gradient.
std::vector<Point> feature_starts(const WarpProblem& problem, Direction direction) {
  const double t = direction == Direction::kForward ? 0.0 : 1.0;
  std::vector<Point> out;
  for (const PositionalTrajectory& f : problem.positional()) out.push_back(f.start + t * f.velocity);
  for (const GradientTrajectory& g : problem.gradient()) out.push_back(g.start + t * g.velocity);
  return out;
}

// A pathline that follows a feature's trajectory has no position error to estimate (its velocity is the
// feature's, constant), and the Jacobian is not error-controlled, on either backend (as on the CPU, the positions
// steer the steps): a batch of such points alone takes a few maximal steps and gets Jacobians off by up to O(1).
// In a lattice or grid they share other points' steps (batches of 64 consecutive points on the CPU, 64 neighbours
// in Morton order on the device); here each gets companions `spread` px around it, next to it in the list.
void add_with_companions(std::vector<Point>& points, Point p, int companions, double spread) {
  points.push_back(p);
  for (int c = 0; c < companions; ++c) points.push_back(p + std::polar(spread * (1.0 + 0.5 * (c % 2)), 2.4 * c + 0.3));
}

// Random points in and around the features' box, a cluster, and every `feature_stride`-th feature's start
// position with two companions.
std::vector<Point> probe_points(const WarpProblem& problem, const ProblemSpec& spec, Direction direction,
                                int random_count, int cluster_count, std::size_t feature_stride, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-0.25 * spec.width, 1.25 * spec.width);
  std::uniform_real_distribution<double> y(-0.25 * spec.height, 1.25 * spec.height);
  std::normal_distribution<double> cluster(0.0, 0.7);
  std::vector<Point> points;
  points.reserve(static_cast<std::size_t>(random_count) + static_cast<std::size_t>(cluster_count));
  for (int i = 0; i < random_count; ++i) points.emplace_back(x(rng), y(rng));
  for (int i = 0; i < cluster_count; ++i) {
    points.emplace_back(0.5 * spec.width + cluster(rng), 0.4 * spec.height + cluster(rng));
  }
  const std::vector<Point> features = feature_starts(problem, direction);
  for (std::size_t f = 0; f < features.size(); f += feature_stride) add_with_companions(points, features[f], 2, 3.0);
  return points;
}

struct ParityCase {
  std::string name;
  ProblemSpec problem;
  OpenClPrecision precision;
  double position_bound;  // px
  double jacobian_bound;  // max ‖ΔJ‖ / ‖J‖
};

class JacobianParity : public ::testing::TestWithParam<ParityCase> {};

// Against the CPU reference at 1/100 of the tolerance (≈ the exact flow): the device's positions within the
// tolerance, its Jacobians within the bound. The Jacobian's error is that of the integration: J is not
// error-controlled (the positions steer the steps, on the CPU too), and it is the variation of the positions'
// error from point to point: up to ~tolerance / 1 px near features, where the field changes fastest (α = 1.5:
// 5.3e-3 measured at 1e-2 px), ~tolerance / 100 px elsewhere (≤ 9e-8 measured at 1e-5 px), plus rounding
// (float32: ~1e-6 relative over a pathline's steps). Bounds: 1e-2 for float32 at 1e-2 px, 1e-6 for double at
// 1e-5 px.
TEST_P(JacobianParity, MatchesTheCpuVariationalEquation) {
  const ParityCase& c = GetParam();
  const WarpProblem problem = make_problem(c.problem);
  const WarpProblem reference = with_tolerance(problem, 1e-2 * c.problem.tolerance_px);
  OpenClWarpBackend opencl(testing::opencl_options("", "", c.precision));
  CpuBackend cpu;
  for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
    const char* way = direction == Direction::kForward ? "forward" : "inverse";
    const bool large = c.problem.count > 100;  // fewer points: the CPU reference's time
    std::vector<Point> expected =
        probe_points(problem, c.problem, direction, large ? 20 : 120, large ? 10 : 30, large ? 8 : 1, 31);
    std::vector<Point> actual = expected;
    std::vector<FlowJacobian> jexp(expected.size());
    std::vector<FlowJacobian> jact(actual.size());
    cpu.flow_points_with_jacobian(reference, expected, jexp, direction, {});
    opencl.flow_points_with_jacobian(problem, actual, jact, direction, {});
    EXPECT_EQ(opencl.last_run_stats().double_precision, c.precision == OpenClPrecision::kDouble);
    const double dp = max_difference(actual, expected);
    const double dj = max_relative_difference(jact, jexp);
    EXPECT_LE(dp, c.position_bound) << c.name << " " << way;
    EXPECT_LE(dj, c.jacobian_bound) << c.name << " " << way;
    RecordProperty(std::string("max_position_difference_px_") + way, scientific(dp));
    RecordProperty(std::string("max_relative_jacobian_difference_") + way, scientific(dj));
  }
}

constexpr auto kFloat = OpenClPrecision::kFloat;
constexpr auto kDouble = OpenClPrecision::kDouble;
constexpr double kFloatJacobianBound = 1e-2;   // at tolerance 1e-2 px: see JacobianParity
constexpr double kDoubleJacobianBound = 1e-6;  // at tolerance 1e-5 px

INSTANTIATE_TEST_SUITE_P(
    RandomSets, JacobianParity,
    ::testing::Values(
        ParityCase{"n2_gradient_float", spec(2, 1, 2.0, 1e-2, 97, 61, 41), kFloat, 1e-2, kFloatJacobianBound},
        ParityCase{"n5_gradients_float", spec(5, 2, 1.5, 1e-2, 97, 61, 42), kFloat, 1e-2, kFloatJacobianBound},
        ParityCase{"n20_alpha3_float", spec(20, 0, 3.0, 1e-2, 128, 96, 43), kFloat, 1e-2, kFloatJacobianBound},
        ParityCase{"n50_float", spec(50, 0, 2.0, 1e-2, 160, 120, 44), kFloat, 1e-2, kFloatJacobianBound},
        ParityCase{"n200_gradients_float", spec(200, 20, 2.0, 1e-2, 320, 240, 45), kFloat, 1e-2, kFloatJacobianBound},
        ParityCase{"n2_gradient_double", spec(2, 1, 2.0, 1e-5, 97, 61, 41), kDouble, 1e-5, kDoubleJacobianBound},
        ParityCase{"n5_gradients_double", spec(5, 2, 1.5, 1e-5, 97, 61, 42), kDouble, 1e-5, kDoubleJacobianBound},
        ParityCase{"n20_alpha3_double", spec(20, 0, 3.0, 1e-5, 128, 96, 43), kDouble, 1e-5, kDoubleJacobianBound},
        ParityCase{"n50_double", spec(50, 0, 2.0, 1e-5, 160, 120, 44), kDouble, 1e-5, kDoubleJacobianBound},
        ParityCase{"n200_gradients_double", spec(200, 20, 2.0, 1e-5, 320, 240, 45), kDouble, 1e-5,
                   kDoubleJacobianBound}),
    [](const ::testing::TestParamInfo<ParityCase>& param) { return param.param.name; });

// Central differences (step 1e-3 px) of the device's own map at tolerance 1e-7 px in the double kernel, each
// point's four probes in one call so that they share a step sequence: truncation O(step²·|∇³f|) ~ 1e-8, the
// flows' error variation ~ tolerance / 10 px, rounding ~ 1e-16·|p| / step ~ 1e-11.
TEST(JacobianAccuracy, MatchesCentralDifferencesOfTheDeviceMap) {
  const ProblemSpec s = spec(25, 4, 2.0, 1e-7, 128, 96, 47);
  const WarpProblem problem = make_problem(s);
  OpenClWarpBackend opencl(testing::opencl_options("", "", kDouble));
  const double step = 1e-3;
  for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
    std::vector<Point> points;
    points.reserve(40);
    std::mt19937 rng(48);
    std::uniform_real_distribution<double> x(0.0, s.width), y(0.0, s.height);
    for (int i = 0; i < 40; ++i) points.emplace_back(x(rng), y(rng));
    std::vector<Point> ends = points;
    std::vector<FlowJacobian> jac(points.size());
    opencl.flow_points_with_jacobian(problem, ends, jac, direction, {});
    std::vector<FlowJacobian> differences;
    for (const Point p : points) {
      std::vector<Point> probes{p + Point(step, 0.0), p - Point(step, 0.0), p + Point(0.0, step), p - Point(0.0, step)};
      opencl.flow_points(problem, probes, direction, {});
      differences.push_back(
          FlowJacobian{(probes[0] - probes[1]) / (2.0 * step), (probes[2] - probes[3]) / (2.0 * step)});
    }
    const double dj = max_relative_difference(jac, differences);
    EXPECT_LE(dj, 1e-6) << (direction == Direction::kForward ? "forward" : "inverse");
    RecordProperty(direction == Direction::kForward ? "max_relative_difference_forward"
                                                    : "max_relative_difference_inverse",
                   scientific(dj));
  }
}

// Exactly at every feature's start position and 1e-6 px from it in eight directions (where ∇ln of the nearest
// weight is ~1e6 px⁻¹), with companions (see add_with_companions): finite Jacobians equal to the CPU
// reference's (at 1e-9 px), in both kernels, within the parity tests' bounds.
TEST(JacobianAccuracy, AtAndNextToFeaturesFiniteAndEqualToTheCpu) {
  const ProblemSpec s = spec(12, 3, 2.0, 1e-2, 128, 96, 49);
  const WarpProblem coarse = make_problem(s);
  const WarpProblem reference = with_tolerance(coarse, 1e-9);
  CpuBackend cpu;
  struct Kernel {
    OpenClPrecision precision;
    double tolerance;
    double bound;
  };
  for (const Kernel k : {Kernel{kFloat, 1e-2, kFloatJacobianBound}, Kernel{kDouble, 1e-5, kDoubleJacobianBound}}) {
    const WarpProblem problem = with_tolerance(coarse, k.tolerance);
    OpenClWarpBackend opencl(testing::opencl_options("", "", k.precision));
    for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
      std::vector<Point> points;
      for (const Point f : feature_starts(problem, direction)) {
        add_with_companions(points, f, 4, 2.0);
        for (int a = 0; a < 8; ++a) points.push_back(f + std::polar(1e-6, 0.25 * M_PI * a + 0.1));
      }
      std::vector<Point> expected = points;
      std::vector<FlowJacobian> jexp(points.size());
      std::vector<FlowJacobian> jact(points.size());
      cpu.flow_points_with_jacobian(reference, expected, jexp, direction, {});
      opencl.flow_points_with_jacobian(problem, points, jact, direction, {});
      const std::string what = std::string(k.precision == kFloat ? "float_" : "double_") +
                               (direction == Direction::kForward ? "forward" : "inverse");
      EXPECT_LE(max_difference(points, expected), k.tolerance) << what;
      const double dj = max_relative_difference(jact, jexp);
      EXPECT_LE(dj, k.bound) << what;
      RecordProperty("max_relative_difference_" + what, scientific(dj));
    }
  }
}

// A point that moves with a feature has no position error to steer its steps: alone in a work-item (the
// padding repeats it) its Jacobian's own error estimate must, as on the CPU.
TEST(JacobianAccuracy, OnAFeatureTrajectoryAloneInItsWorkItem) {
  const WarpProblem coarse = make_problem(spec(30, 4, 2.0, 1e-2, 128, 96, 5));
  const WarpProblem reference = with_tolerance(coarse, 1e-9);
  CpuBackend cpu;
  OpenClWarpBackend opencl(testing::opencl_options("", "", kDouble));
  const WarpProblem problem = with_tolerance(coarse, 1e-7);
  double worst = 0.0;
  for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
    for (const Point f : feature_starts(problem, direction)) {
      std::vector<Point> expected = {f};
      std::vector<Point> actual = {f};
      std::vector<FlowJacobian> jexp(1);
      std::vector<FlowJacobian> jact(1);
      cpu.flow_points_with_jacobian(reference, expected, jexp, direction, {});
      opencl.flow_points_with_jacobian(problem, actual, jact, direction, {});
      worst = std::max(worst, max_relative_difference(jact, jexp));
    }
  }
  EXPECT_LE(worst, 1e-5);
  RecordProperty("max_relative_difference", scientific(worst));
}

// P = Q everywhere: W is the identity, J = I.
TEST(JacobianClosedForm, IdentityMapGivesTheIdentity) {
  std::vector<Feature> features;
  for (const Point p : {Point(10, 20), Point(60, 25), Point(35, 70), Point(80, 80)}) {
    Feature f;
    f.source = p;
    f.target = p;
    features.push_back(f);
  }
  const WarpProblem problem(features, WarpOptions{});
  for (const OpenClPrecision precision : {kFloat, kDouble}) {
    OpenClWarpBackend opencl(testing::opencl_options("", "", precision));
    std::vector<Point> points{Point(0, 0), Point(10, 20), Point(47.25, 51.5), Point(200, -30)};
    const std::vector<Point> start = points;
    std::vector<FlowJacobian> jac(points.size());
    for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
      map_points_with_jacobian(opencl, problem, points, jac, direction);
      EXPECT_LE(max_difference(points, start), 1e-9);
      EXPECT_LE(max_relative_difference(jac, std::vector<FlowJacobian>(points.size())), 1e-6);
    }
  }
}

// Two positional features without pre-alignment: the field is the single pair's similarity velocity (Eq. 3),
// so W is the similarity that maps P_1, P_2 to Q_1, Q_2 and its Jacobian is the multiplication by
// a = (Q_2 − Q_1) / (P_2 − P_1) (columns a, i·a; a⁻¹ for the inverse). With pre-alignment the flow is the
// identity and map_points_with_jacobian gives the pre-alignment's linear part: the same a.
TEST(JacobianClosedForm, TwoFeaturesGiveTheSimilaritysLinearPart) {
  Feature f1, f2;
  f1.source = Point(20, 30);
  f1.target = Point(26, 28);
  f2.source = Point(90, 50);
  f2.target = Point(88, 71);
  const Point a = (f2.target - f1.target) / (f2.source - f1.source);
  for (const Prealign prealign : {Prealign::kNone, Prealign::kSimilarity}) {
    for (const OpenClPrecision precision : {kFloat, kDouble}) {
      WarpOptions options;
      options.prealign = prealign;
      options.tolerance_px = precision == kFloat ? 1e-2 : 1e-6;
      const WarpProblem problem({f1, f2}, options);
      OpenClWarpBackend opencl(testing::opencl_options("", "", precision));
      for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
        const Point m = direction == Direction::kForward ? a : 1.0 / a;
        std::vector<Point> points{Point(0, 0), Point(20, 30), Point(55, 41), Point(88, 71), Point(140, -20)};
        std::vector<FlowJacobian> jac(points.size());
        map_points_with_jacobian(opencl, problem, points, jac, direction);
        const std::vector<FlowJacobian> expected(points.size(), FlowJacobian{m, Point(0, 1) * m});
        EXPECT_LE(max_relative_difference(jac, expected), precision == kFloat ? 1e-5 : 1e-9)
            << (prealign == Prealign::kNone ? "no pre-alignment " : "pre-aligned ")
            << (precision == kFloat ? "float " : "double ")
            << (direction == Direction::kForward ? "forward" : "inverse");
      }
    }
  }
}

}  // namespace
}  // namespace texwarp
