// The OpenCL backend's runtime behaviour: device choice and its errors, the device list, POCL_CACHE_DIR, tiles
// on wide odd-sized outputs, progress, cancellation between tiles, precision choice, concurrent calls, the first
// OpenCL calls made by several threads at once, and a cold kernel build that prints nothing.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>
#include <vector>

#include "kernel_test_support.hpp"
#include "test_folder.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/numerical_error.hpp"
#include "texwarp/kernels/opencl_backend.hpp"
#include "texwarp/kernels/opencl_error.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {
namespace {

using testing::make_problem;
using testing::max_difference;
using testing::ProblemSpec;

TEST(OpenClDevices, UnknownDeviceIsAClearError) {
  try {
    make_opencl_backend(testing::opencl_options("", "no-such-device-xyz"));
    FAIL() << "expected OpenClError";
  } catch (const OpenClError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no-such-device-xyz"), std::string::npos) << what;
    EXPECT_NE(what.find("available"), std::string::npos) << what;
  }
}

TEST(OpenClDevices, UnknownPlatformIsAClearError) {
  EXPECT_THROW(make_opencl_backend(testing::opencl_options("no-such-platform-xyz", "")), OpenClError);
}

TEST(OpenClDevices, ListHasOneDefaultAndTheDefaultIsACpu) {
  const std::vector<std::string> lines = list_opencl_devices();
  ASSERT_FALSE(lines.empty());
  int defaults = 0;
  for (const std::string& line : lines) {
    if (line.find("[default]") != std::string::npos) {
      ++defaults;
      EXPECT_NE(line.find("(cpu,"), std::string::npos) << line;
    }
  }
  EXPECT_EQ(defaults, 1);
}

TEST(OpenClDevices, SelectionByTypeAndName) {
  auto backend = make_opencl_backend(testing::opencl_options("", "cpu"));
  ASSERT_NE(backend, nullptr);
  EXPECT_EQ(backend->name(), "opencl");
  const auto* opencl = dynamic_cast<const OpenClWarpBackend*>(backend.get());
  ASSERT_NE(opencl, nullptr);
  EXPECT_NE(opencl->device_description().find('('), std::string::npos);
  EXPECT_NO_THROW(make_opencl_backend(testing::opencl_options("", "all")));
}

TEST(OpenClDevices, PoclCacheDirectoryIsSet) {
  make_opencl_backend();
  const char* dir = std::getenv("POCL_CACHE_DIR");
  ASSERT_NE(dir, nullptr);
  EXPECT_NE(std::string(dir), "");
}

TEST(OpenClTiles, WideOddOutputMatchesTheCpuReference) {
  // Wider than PoCL's largest image (8192) and not a multiple of the 16×4 work-item block.
  ProblemSpec s;
  s.count = 12;
  s.gradient_count = 2;
  s.width = 8300.0;
  s.height = 40.0;
  s.max_displacement = 12.0;
  s.seed = 5;
  const WarpProblem problem = make_problem(s);
  OpenClWarpBackend opencl;
  const int w = 8209, h = 3;
  const std::vector<Point> grid = opencl.inverse_map_grid(problem, w, h, {});
  ASSERT_EQ(grid.size(), static_cast<std::size_t>(w * h));
  // The CPU reference on every 7th column.
  std::vector<Point> expected;
  std::vector<Point> actual;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; x += 7) {
      expected.emplace_back(x + 0.5, y + 0.5);
      actual.push_back(grid[static_cast<std::size_t>(y) * w + x]);
    }
  }
  CpuBackend cpu;
  map_points(cpu, problem, expected, Direction::kInverse);
  EXPECT_LE(max_difference(actual, expected), 1e-3);
}

// A problem heavy enough for several tiles on a small grid.
WarpProblem tiled_problem() {
  ProblemSpec s;
  s.count = 120;
  s.width = 400.0;
  s.height = 300.0;
  s.tolerance_px = 1e-2;
  s.seed = 9;
  return make_problem(s);
}

TEST(OpenClRun, ProgressIsMonotoneAndReachesOne) {
  const WarpProblem problem = tiled_problem();
  OpenClWarpBackend opencl;
  std::vector<double> seen;
  RunControl control;
  control.progress = [&](double f) { seen.push_back(f); };
  opencl.inverse_map_grid(problem, 200, 150, control);
  ASSERT_GE(seen.size(), 2u) << "expected several tiles";
  for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_GT(seen[i], seen[i - 1]);
  EXPECT_DOUBLE_EQ(seen.back(), 1.0);
  EXPECT_EQ(opencl.last_run_stats().launches, seen.size());
}

TEST(OpenClRun, CancellationBeforeTheFirstTile) {
  const WarpProblem problem = tiled_problem();
  OpenClWarpBackend opencl;
  std::atomic<bool> cancel{true};
  RunControl control;
  control.cancel = &cancel;
  EXPECT_THROW(opencl.inverse_map_grid(problem, 200, 150, control), CanceledError);
  std::vector<Point> points(1000, Point(50.0, 50.0));
  EXPECT_THROW(map_points(opencl, problem, points, Direction::kForward, control), CanceledError);
}

TEST(OpenClRun, CancellationBetweenTiles) {
  const WarpProblem problem = tiled_problem();
  OpenClWarpBackend opencl;
  std::atomic<bool> cancel{false};
  int calls = 0;
  RunControl control;
  control.cancel = &cancel;
  control.progress = [&](double) {
    ++calls;
    cancel = true;
  };
  EXPECT_THROW(opencl.inverse_map_grid(problem, 200, 150, control), CanceledError);
  EXPECT_EQ(calls, 1);
}

TEST(OpenClRun, PrecisionFollowsTheTolerance) {
  ProblemSpec s;
  s.tolerance_px = 1e-2;
  OpenClWarpBackend opencl;
  opencl.inverse_map_grid(make_problem(s), 17, 5, {});
  EXPECT_FALSE(opencl.last_run_stats().double_precision);
  s.tolerance_px = 1e-4;
  opencl.inverse_map_grid(make_problem(s), 17, 5, {});
  EXPECT_TRUE(opencl.last_run_stats().double_precision);
  OpenClWarpBackend forced(testing::opencl_options("", "", OpenClPrecision::kFloat));
  forced.inverse_map_grid(make_problem(s), 17, 5, {});
  EXPECT_FALSE(forced.last_run_stats().double_precision);
}

// Twelve pins of a cylinder's crossing pin set (the pinned-unwrap benchmark's case 33), rounded to 1e-3 px: the
// straight trajectories of pin-v674 and pin-v683 pass 0.73 px apart, where float32's rounding of the field keeps the
// step's error estimate above the 0.01 px tolerance however short the step.
std::vector<Feature> close_pass_features() {
  const double pins[12][4] = {
      {461.661, 328.41, 297.333, 119.537}, {354.452, 258.226, 380.0, 153.653},   {351.476, 359.034, 256.0, 153.653},
      {292.167, 5.12, 35.556, 204.826},    {268.017, 188.312, 214.667, 221.884}, {239.655, 293.057, 435.111, 256.0},
      {261.455, 401.021, 311.111, 256.0},  {158.524, 450.475, 448.889, 358.347}, {140.924, 87.109, 159.556, 375.405},
      {143.669, 157.826, 35.556, 375.405}, {138.272, 250.715, 393.778, 392.463}, {138.96, 359.414, 269.778, 392.463}};
  std::vector<Feature> features;
  for (const auto& p : pins) features.push_back({"", {p[0], p[1]}, {p[2], p[3]}, {}, {}});
  return features;
}

TEST(OpenClRun, StepsThatCollapseInFloat32AreIntegratedAgainInDouble) {
  const WarpProblem problem(close_pass_features(), WarpOptions{});  // 0.01 px: float32 under kAuto
  ASSERT_GE(problem.tolerance_px(), kFloatMinTolerancePx);
  CpuBackend cpu;
  OpenClWarpBackend forced(testing::opencl_options("", "", OpenClPrecision::kFloat));
  OpenClWarpBackend opencl;
  std::vector<double> reported;
  RunControl control;
  control.progress = [&](double f) { reported.push_back(f); };
  auto expect_retried = [&] {
    EXPECT_TRUE(opencl.last_run_stats().retried_in_double);
    EXPECT_TRUE(opencl.last_run_stats().double_precision);
    EXPECT_TRUE(std::is_sorted(reported.begin(), reported.end())) << "progress went back";
    reported.clear();
  };
  // The output's pixels (the grid kernel, pathlines backward).
  EXPECT_THROW(forced.inverse_map_grid(problem, 512, 512, {}), NumericalError);
  const std::vector<Point> grid = opencl.inverse_map_grid(problem, 512, 512, control);
  expect_retried();
  EXPECT_EQ(opencl.double_retries(), 1u);  // what a job's report counts
  EXPECT_EQ(forced.double_retries(), 0u);
  // Against the CPU reference (double) on every 7th pixel, the close pass's neighbourhood among them.
  std::vector<Point> pixels;
  std::vector<Point> from_grid;
  for (std::size_t i = 0; i < grid.size(); i += 7) {
    const std::size_t column = i % 512;
    const std::size_t row = i / 512;
    pixels.emplace_back(static_cast<double>(column) + 0.5, static_cast<double>(row) + 0.5);
    from_grid.push_back(grid[i]);
  }
  map_points(cpu, problem, pixels, Direction::kInverse, {});
  EXPECT_LE(max_difference(from_grid, pixels), 2.0 * problem.tolerance_px());
  // Points of the source forward (a mesh's vertices), every other pixel.
  std::vector<Point> points;
  for (int y = 0; y < 512; y += 2) {
    for (int x = 0; x < 512; x += 2) points.emplace_back(x, y);
  }
  std::vector<Point> in_float = points;
  EXPECT_THROW(map_points(forced, problem, in_float, Direction::kForward, {}), NumericalError);
  std::vector<Point> mapped = points;
  map_points(opencl, problem, mapped, Direction::kForward, control);
  expect_retried();
  EXPECT_EQ(opencl.double_retries(), 2u);
  std::vector<Point> sample;
  std::vector<Point> from_opencl;
  for (std::size_t i = 0; i < points.size(); i += 7) {
    sample.push_back(points[i]);
    from_opencl.push_back(mapped[i]);
  }
  map_points(cpu, problem, sample, Direction::kForward, {});
  EXPECT_LE(max_difference(from_opencl, sample), 2.0 * problem.tolerance_px());
  // Where float32 holds, kAuto keeps it.
  std::vector<Point> far_away = {Point(10.0, 10.0)};
  map_points(opencl, problem, far_away, Direction::kForward, {});
  EXPECT_FALSE(opencl.last_run_stats().retried_in_double);
  EXPECT_FALSE(opencl.last_run_stats().double_precision);
  EXPECT_EQ(opencl.double_retries(), 2u);
  EXPECT_EQ(cpu.double_retries(), 0u);
}

TEST(OpenClRun, ConcurrentCallsOnOneBackendGiveTheSequentialResults) {
  ProblemSpec a;
  a.count = 15;
  a.seed = 31;
  ProblemSpec b = a;
  b.count = 25;
  b.alpha = 3.0;
  b.seed = 32;
  const WarpProblem pa = make_problem(a);
  const WarpProblem pb = make_problem(b);
  OpenClWarpBackend opencl;
  const std::vector<Point> ea = opencl.inverse_map_grid(pa, 61, 37, {});
  const std::vector<Point> eb = opencl.inverse_map_grid(pb, 61, 37, {});
  std::vector<Point> ra, rb;
  std::thread ta([&] { ra = opencl.inverse_map_grid(pa, 61, 37, {}); });
  std::thread tb([&] { rb = opencl.inverse_map_grid(pb, 61, 37, {}); });
  ta.join();
  tb.join();
  EXPECT_EQ(max_difference(ra, ea), 0.0);
  EXPECT_EQ(max_difference(rb, eb), 0.0);
}

TEST(OpenClRun, DegenerateSizesAndProblems) {
  OpenClWarpBackend opencl;
  const WarpProblem none(std::vector<Feature>{}, WarpOptions{});
  EXPECT_TRUE(opencl.inverse_map_grid(none, 0, 10, {}).empty());
  const std::vector<Point> id = opencl.inverse_map_grid(none, 3, 2, {});
  ASSERT_EQ(id.size(), 6u);
  EXPECT_EQ(id[5], Point(2.5, 1.5));
  const WarpProblem problem = make_problem({});
  EXPECT_EQ(opencl.inverse_map_grid(problem, 1, 1, {}).size(), 1u);
}

// The first OpenCL calls of a process, made by several threads at once (texwarpd's workers at start): each run is
// a fresh process (a threadsafe death test re-runs this binary), where PoCL crashed or said "no platform" before.
TEST(OpenClStartup, ThreadsOpeningTheFirstDeviceTogetherAllGetIt) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  for (int run = 0; run < 4; ++run) {
    EXPECT_EXIT(
        {
          std::atomic<int> opened{0};
          std::vector<std::thread> threads;
          threads.reserve(4);
          for (int i = 0; i < 4; ++i) {
            threads.emplace_back([&opened] {
              try {
                if (make_opencl_backend() != nullptr) ++opened;
              } catch (const std::exception& e) {
                std::fprintf(stderr, "%s\n", e.what());
              }
            });
          }
          for (auto& t : threads) t.join();
          std::exit(opened.load() == 4 ? 0 : 1);
        },
        ::testing::ExitedWithCode(0), "");
  }
}

// A build that is not in PoCL's cache: the compiler's warnings stay out of stderr.
TEST(OpenClStartup, AColdBuildPrintsNoCompilerOutput) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const texwarp::testing::TestFolder cache{"cold-pocl-cache"};
  EXPECT_EXIT(
      {
        ::setenv("POCL_CACHE_DIR", cache.path().c_str(), 1);
        OpenClWarpBackend opencl;
        const std::vector<Point> grid = opencl.inverse_map_grid(make_problem({}), 16, 8, {});
        // The child re-ran this test and made its own folder (its pid in the name); std::exit skips its removal.
        std::error_code ignored;
        std::filesystem::remove_all(cache.path(), ignored);
        std::exit(grid.size() == 128 ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), ::testing::Not(::testing::HasSubstr("warning")));
}

}  // namespace
}  // namespace texwarp
