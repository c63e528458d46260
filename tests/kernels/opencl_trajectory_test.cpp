// Planned trajectories (issue 13) on the OpenCL backend: feature sets whose straight trajectories collide, every
// pixel of a grid (the grid kernel runs the last segment, points the others) and Jacobians chained over the
// segments, held to the CPU reference within the parity tests' bounds, in float32 and double; every pixel (exact grids
// and the certified lattice) against the CPU at 1e-9 px.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "crossing_features.hpp"
#include "kernel_test_support.hpp"
#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {
namespace {

using testing::max_difference;

constexpr double kSize = 96.0;

std::string set_name(const ::testing::TestParamInfo<testing::CrossingSet>& p) { return p.param.name; }

class TrajectoryParity : public ::testing::TestWithParam<testing::CrossingSet> {};

// Grids as opencl_parity_test: 1e-3 px in float32 at tolerance 1e-3 px, 1e-4 px in double at 1e-5 px.
TEST_P(TrajectoryParity, EveryPixelMatchesTheCpuReference) {
  for (const auto& [tolerance, precision, bound] :
       {std::tuple{1e-3, OpenClPrecision::kAuto, 1e-3}, std::tuple{1e-5, OpenClPrecision::kDouble, 1e-4}}) {
    WarpOptions options = GetParam().options;
    options.tolerance_px = tolerance;
    const WarpProblem problem(GetParam().features, options);
    ASSERT_GE(problem.segments().size(), 2u);
    OpenClWarpBackend opencl(testing::opencl_options("", "", precision));
    CpuBackend cpu;
    const std::vector<Point> expected = cpu.inverse_map_grid(problem, 41, 37, {});
    const std::vector<Point> actual = opencl.inverse_map_grid(problem, 41, 37, {});
    EXPECT_LE(max_difference(actual, expected), bound) << GetParam().name << " tolerance " << tolerance;
    const auto moving = std::count_if(problem.segments().begin(), problem.segments().end(),
                                      [](const TrajectorySegment& s) { return !s.field_is_zero; });
    EXPECT_EQ(opencl.last_run_stats().points, actual.size() * static_cast<std::size_t>(moving));
  }
}

// Jacobians as opencl_jacobian_test: float32 at 1e-2 px against the CPU at 1e-4 px: positions within the
// tolerance, ‖ΔJ‖/‖J‖ ≤ 1e-2.
TEST_P(TrajectoryParity, ChainedJacobiansMatchTheCpuReference) {
  WarpOptions options = GetParam().options;
  options.tolerance_px = 1e-2;
  const WarpProblem problem(GetParam().features, options);
  options.tolerance_px = 1e-4;
  const WarpProblem reference(GetParam().features, options);
  ASSERT_EQ(reference.trajectory_plan().waypoints, problem.trajectory_plan().waypoints);
  OpenClWarpBackend opencl(testing::opencl_options("", "", OpenClPrecision::kFloat));
  CpuBackend cpu;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, kSize);
  std::vector<Point> points(60);
  for (Point& p : points) p = Point(u(rng), u(rng));
  for (const Direction direction : {Direction::kForward, Direction::kInverse}) {
    std::vector<Point> expected = points;
    std::vector<Point> actual = points;
    std::vector<FlowJacobian> jexp(points.size());
    std::vector<FlowJacobian> jact(points.size());
    cpu.flow_points_with_jacobian(reference, expected, jexp, direction, {});
    opencl.flow_points_with_jacobian(problem, actual, jact, direction, {});
    EXPECT_LE(max_difference(actual, expected), 1e-2) << GetParam().name;
    double worst = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double norm = std::max(std::abs(jexp[i].dx), std::abs(jexp[i].dy));
      worst = std::max({worst, std::abs(jact[i].dx - jexp[i].dx) / norm, std::abs(jact[i].dy - jexp[i].dy) / norm});
      EXPECT_GT(jact[i].det(), 0.0) << GetParam().name;
    }
    EXPECT_LE(worst, 1e-2) << GetParam().name;
  }
}

// The tolerance holds where an inverse map's points land (WarpProblem::pathline_tolerance_px): the permuted grids are
// pre-aligned by a similarity of scale 0.5, whose inverse doubles the flow's errors. The float32 kernel at 0.01 and
// 0.05 px, points every 4 px over the whole image, against the CPU reference at 1e-9 px.
TEST_P(TrajectoryParity, InverseMapsMeetTheToleranceWhereTheirPointsLand) {
  std::vector<Point> start;
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 24; ++x) start.emplace_back(4.0 * x + 1.5, 4.0 * y + 1.5);
  }
  WarpOptions options = GetParam().options;
  options.tolerance_px = 1e-9;
  const WarpProblem tight(GetParam().features, options);
  CpuBackend cpu;
  std::vector<Point> truth = start;
  map_points(cpu, tight, truth, Direction::kInverse);
  OpenClWarpBackend opencl(testing::opencl_options("", "", OpenClPrecision::kFloat));
  for (const double tolerance : {1e-2, 5e-2}) {
    options.tolerance_px = tolerance;
    const WarpProblem problem(GetParam().features, options);
    std::vector<Point> actual = start;
    map_points(opencl, problem, actual, Direction::kInverse);
    EXPECT_LE(max_difference(actual, truth), tolerance) << GetParam().name << " at " << tolerance << " px";
  }
}

// Every pixel of the 96² image against the CPU's points at 1e-9 px, at 0.01 and 0.05 px: the exact grid of both
// backends (OpenCL's grid kernel runs the last segment, float32) and the certified lattice within its bound. The
// segments' errors grow through the later segments (flow_growth.hpp): before the growth scale the permuted grid with
// gradient features missed 0.05 px by 1.28× on the CPU, 1.14× in the grid kernel and 1.44× in the lattice.
TEST_P(TrajectoryParity, EveryPixelMeetsTheToleranceWhereItLands) {
  constexpr int kPixels = static_cast<int>(kSize);
  std::vector<Point> truth;
  for (int y = 0; y < kPixels; ++y) {
    for (int x = 0; x < kPixels; ++x) truth.emplace_back(x + 0.5, y + 0.5);
  }
  WarpOptions options = GetParam().options;
  options.tolerance_px = 1e-9;
  CpuBackend cpu;
  map_points(cpu, WarpProblem(GetParam().features, options), truth, Direction::kInverse);
  OpenClWarpBackend opencl(testing::opencl_options("", "", OpenClPrecision::kFloat));
  for (const double tolerance : {1e-2, 5e-2}) {
    options.tolerance_px = tolerance;
    const WarpProblem problem(GetParam().features, options);
    EXPECT_LE(max_difference(opencl.inverse_map_grid(problem, kPixels, kPixels, {}), truth), tolerance)
        << GetParam().name << ": OpenCL at " << tolerance << " px";
    EXPECT_LE(max_difference(cpu.inverse_map_grid(problem, kPixels, kPixels, {}), truth), tolerance)
        << GetParam().name << ": CPU at " << tolerance << " px";
    CertifiedGridOptions lattice;
    lattice.tolerance_px = tolerance;
    WarpCertificate certificate;
    const std::vector<Point> interpolated =
        certified_inverse_map_grid(opencl, problem, kPixels, kPixels, lattice, {}, certificate);
    EXPECT_LE(certificate.max_error_px_bound, tolerance) << GetParam().name;
    EXPECT_LE(max_difference(interpolated, truth), certificate.max_error_px_bound)
        << GetParam().name << ": the lattice at " << tolerance << " px";
  }
}

INSTANTIATE_TEST_SUITE_P(RefusedBeforePlanning, TrajectoryParity,
                         ::testing::ValuesIn(testing::crossing_sets(kSize, false, 1e-3)), set_name);

}  // namespace
}  // namespace texwarp
