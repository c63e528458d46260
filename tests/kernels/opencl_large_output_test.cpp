// Soak test: an 8192² output (PoCL's largest 2D image, and 1 GiB of doubles in the result) through the OpenCL
// backend in tiles, checked against the CPU reference on a sparse sample of pixels.
#include <gtest/gtest.h>

#include <random>

#include "kernel_test_support.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {
namespace {

TEST(OpenClLargeOutput, Grid8192SquaredMatchesTheCpuReferenceOnASample) {
  testing::ProblemSpec s;
  s.count = 10;
  s.gradient_count = 2;
  s.width = 8192.0;
  s.height = 8192.0;
  s.max_displacement = 300.0;
  s.tolerance_px = 1e-2;
  s.seed = 8;
  const WarpProblem problem = testing::make_problem(s);
  OpenClWarpBackend opencl;
  const int size = 8192;
  const std::vector<Point> grid = opencl.inverse_map_grid(problem, size, size, {});
  ASSERT_EQ(grid.size(), static_cast<std::size_t>(size) * size);
  EXPECT_GT(opencl.last_run_stats().launches, 1u);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pick(0, size - 1);
  std::vector<Point> expected, actual;
  for (int i = 0; i < 2000; ++i) {
    const int x = pick(rng), y = pick(rng);
    expected.emplace_back(x + 0.5, y + 0.5);
    actual.push_back(grid[static_cast<std::size_t>(y) * size + x]);
  }
  CpuBackend cpu;
  map_points(cpu, problem, expected, Direction::kInverse);
  // Both at tolerance 1e-2: their difference is bounded by the two integration errors.
  EXPECT_LE(testing::max_difference(actual, expected), 2e-2);
}

}  // namespace
}  // namespace texwarp
