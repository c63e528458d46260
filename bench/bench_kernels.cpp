// texwarp_bench_kernels: the inverse map of every output pixel on the OpenCL backend (PoCL by default) against
// the CPU reference on the same warp, for n positional features × output sizes, and the 1024², 50-feature image
// warp next to OpenCV's thin-plate-spline warp; with --jacobian, the cost of flow_points_with_jacobian against
// flow_points instead. Prints a table; figures, not pass/fail.
//
// Usage: texwarp_bench_kernels [--features 10,50,100,200] [--sizes 512,1024,2048] [--runs 5]
//                              [--cpu-seconds 15] [--no-tps] [--quick] [--jacobian]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "machine_peak.hpp"
#include "random_features.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

#if defined(TEXWARP_BENCH_HAVE_OPENCV)
#include <opencv2/core.hpp>
#include <opencv2/shape.hpp>
#endif

namespace texwarp::bench {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

std::string load_average() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::vector<int> parse_list(const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stoi(item));
  return out;
}

struct Settings {
  std::vector<int> features{10, 50, 100, 200};
  std::vector<int> sizes{512, 1024, 2048};
  int runs = 5;
  double cpu_seconds = 15.0;  // CPU reference budget per case (rows subsampled beyond it)
  bool tps = true;
  bool jacobian = false;  // only the Jacobian cost table
};

// n positional features scattered over a size² texture, displaced by up to size/20 px: the same layout scaled
// for every size (same seed), default options (α = 2, tolerance 0.01 px, similarity pre-alignment).
WarpProblem bench_problem(int n, int size) {
  WarpOptions options;
  testing::RandomFeatureSpec spec;
  spec.count = n;
  spec.width = size;
  spec.height = size;
  spec.margin = size / 32.0;
  spec.max_displacement = size / 20.0;
  spec.seed = 2024;
  return WarpProblem(testing::random_features(spec, options), options);
}

struct CpuSample {
  double seconds_full = 0.0;          // measured, or extrapolated from the rows
  int rows = 0;                       // rows integrated
  double max_diff = 0.0;              // max |OpenCL − CPU| over those rows
  std::vector<std::size_t> compared;  // pixel indices compared, the worst first
  std::vector<Point> cpu_values;      // the CPU reference's values there (from the row runs)
};

// The CPU reference on `rows` evenly spaced rows of the output (all of them when affordable), compared with
// the OpenCL grid; time extrapolated to the whole image by rows.
CpuSample cpu_reference(const WarpProblem& problem, int size, const std::vector<Point>& grid, double budget) {
  CpuBackend cpu;
  std::size_t worst = 0;
  std::vector<Point> cpu_rows;  // the CPU values of the rows run last, row-major
  auto run_rows = [&](const std::vector<int>& ys, double& max_diff) {
    std::vector<Point> points;
    for (int y : ys) {
      for (int x = 0; x < size; ++x) points.emplace_back(x + 0.5, y + 0.5);
    }
    const auto start = Clock::now();
    map_points(cpu, problem, points, Direction::kInverse);
    const double s = seconds_since(start);
    cpu_rows = points;
    for (std::size_t r = 0; r < ys.size(); ++r) {
      for (int x = 0; x < size; ++x) {
        const Point a = grid[static_cast<std::size_t>(ys[r]) * size + x];
        const double d = std::abs(a - points[r * size + static_cast<std::size_t>(x)]);
        if (!(d <= max_diff)) {
          max_diff = std::isfinite(d) ? d : INFINITY;
          worst = static_cast<std::size_t>(ys[r]) * size + x;
        }
      }
    }
    return s;
  };
  CpuSample sample;
  double probe_diff = 0.0;
  const double one_row = run_rows({size / 2}, probe_diff);
  const int rows = std::clamp(static_cast<int>(budget / std::max(one_row, 1e-6)), 1, size);
  std::vector<int> ys;
  ys.reserve(static_cast<std::size_t>(rows));
  for (int r = 0; r < rows; ++r) ys.push_back(static_cast<int>((r + 0.5) * size / rows));
  sample.rows = rows;
  const double s = rows == 1 ? one_row : run_rows(ys, sample.max_diff);
  if (rows == 1) sample.max_diff = probe_diff;
  sample.seconds_full = s * size / rows;
  if (rows == 1) ys = {size / 2};
  auto cpu_value = [&](std::size_t pixel) {
    const int y = static_cast<int>(pixel / static_cast<std::size_t>(size));
    const std::size_t r = static_cast<std::size_t>(std::find(ys.begin(), ys.end(), y) - ys.begin());
    return cpu_rows[r * static_cast<std::size_t>(size) + pixel % static_cast<std::size_t>(size)];
  };
  sample.compared.push_back(worst);
  for (int k = 1; k < 64; ++k) {
    sample.compared.push_back(static_cast<std::size_t>(ys[static_cast<std::size_t>(k) % ys.size()]) * size +
                              static_cast<std::size_t>((k * 997) % size));
  }
  for (const std::size_t pixel : sample.compared) sample.cpu_values.push_back(cpu_value(pixel));
  return sample;
}

// Max errors of the OpenCL grid and of the CPU reference (both at the problem's tolerance) against the CPU at a
// tight tolerance (1e-6 px), on the compared pixels: which of the two a difference comes from.
std::pair<double, double> errors_against_tight(const WarpProblem& problem, int size, const std::vector<Point>& grid,
                                               const CpuSample& sample) {
  WarpOptions tight = problem.options();
  tight.tolerance_px = 1e-6;
  const WarpProblem reference(problem.features(), tight);
  std::vector<Point> exact;
  for (const std::size_t i : sample.compared) {
    const std::size_t column = i % static_cast<std::size_t>(size);
    const std::size_t row = i / static_cast<std::size_t>(size);
    exact.emplace_back(static_cast<double>(column) + 0.5, static_cast<double>(row) + 0.5);
  }
  CpuBackend cpu;
  map_points(cpu, reference, exact, Direction::kInverse);
  double e_opencl = 0.0, e_cpu = 0.0;
  for (std::size_t k = 0; k < exact.size(); ++k) {
    e_opencl = std::max(e_opencl, std::abs(grid[sample.compared[k]] - exact[k]));
    e_cpu = std::max(e_cpu, std::abs(sample.cpu_values[k] - exact[k]));
  }
  return {e_opencl, e_cpu};
}

void print_machine(const MachinePeak& m, const std::string& device) {
  std::printf("machine: %s, %d hardware threads; OpenCL device: %s\n", m.cpu_model.c_str(), m.cores, device.c_str());
  std::printf("FP32 FMA peak = lanes × FMA units × 2 × clock × cores; lanes = %d (AVX-512), FMA units = %d (%s)\n",
              m.lanes, m.fma_units, m.fma_units_note.c_str());
  std::printf("  nominal clock %.3f GHz (/proc/cpuinfo): peak %.1f GFLOP/s\n", m.nominal_ghz,
              m.peak_gflops(m.nominal_ghz));
  if (m.measured_ghz > 0.0) {
    std::printf("  measured clock %.3f GHz (dependent adds, per thread CPU second): peak %.1f GFLOP/s\n",
                m.measured_ghz, m.peak_gflops(m.measured_ghz));
    std::printf("  measured AVX-512 FMA throughput, all cores at once, per thread CPU second: %.1f GFLOP/s "
                "(= %.2f FMA/cycle/core at %.3f GHz)\n",
                m.measured_fma_gflops, m.measured_fma_gflops / (m.lanes * 2.0 * m.measured_ghz * m.cores),
                m.measured_ghz);
  }
}

void run_table(const Settings& settings, const MachinePeak& machine) {
  const double peak_nominal = machine.peak_gflops(machine.nominal_ghz);
  const double peak_measured = machine.measured_ghz > 0.0 ? machine.peak_gflops(machine.measured_ghz) : 0.0;
  std::printf(
      "\nPair-loop flops: 4 per unordered feature pair per point per field evaluation (the multiply-add z_j·c_ij of\n"
      "a real weight and a complex coefficient: 2 FMAs), times n(n−1)/2 pairs, times the field evaluations the\n"
      "kernel reports (7 per accepted DP5 step, 6 per rejected one, summed over the output pixels). Per-point O(n)\n"
      "work (distances, weights, row sums), the per-stage c_ij(t) and the integrator are not counted; the rate is\n"
      "these flops divided by the whole wall time of the call (median of %d runs), so it understates the loop.\n"
      "CPU reference: the same warp (same problem, tolerance, pixel centres) with CpuBackend on all threads; where\n"
      "it would exceed %.0f s it runs on evenly spaced rows and its time is extrapolated by rows (column 'rows').\n\n",
      settings.runs, settings.cpu_seconds);
  std::printf(
      "max|Δ|: OpenCL against the CPU reference over the compared rows. err(ocl), err(cpu): each against the CPU at\n"
      "tolerance 1e-6 px on 64 of those pixels (the worst one included). closest: the closest approach of two\n"
      "feature trajectories (px): near-collisions make the field change fast in time and every DP5 error estimate\n"
      "less reliable. 'cpu use': the benchmark's share of all cores during the OpenCL runs (the machine may be\n"
      "shared); 'GF/s own': the pair-loop flops per second of CPU time the runs got, times the cores.\n\n");
  std::printf("%5s %6s | %9s %8s %8s | %9s %6s %6s | %7s %8s | %9s %5s %8s | %9s %9s %9s | %7s\n", "n", "size",
              "OpenCL s", "Mpx/s", "evals/px", "pair GF/s", "%nom", "%meas", "cpu use", "GF/s own", "CPU s", "rows",
              "speedup", "max|Δ|", "err(ocl)", "err(cpu)", "closest");
  OpenClWarpBackend opencl;
  for (const int n : settings.features) {
    for (const int size : settings.sizes) {
      const WarpProblem problem = bench_problem(n, size);
      opencl.inverse_map_grid(problem, 16, 4, {});  // program build and first-use costs out of the timing
      std::vector<double> times;
      std::vector<Point> grid;
      OpenClRunStats stats;
      const double cpu0 = process_cpu_seconds();
      const auto wall0 = Clock::now();
      for (int r = 0; r < settings.runs; ++r) {
        grid = opencl.inverse_map_grid(problem, size, size, {});
        stats = opencl.last_run_stats();
        times.push_back(stats.seconds);
      }
      const double cpu_used = process_cpu_seconds() - cpu0;
      const double cpu_share = cpu_used / seconds_since(wall0) / machine.cores;
      const double t = median(times);
      const double pixels = static_cast<double>(size) * size;
      const double pairs = 0.5 * n * (n - 1.0);
      const double gflops = static_cast<double>(stats.point_evaluations) * pairs * 4.0 / t / 1e9;
      const CpuSample cpu = cpu_reference(problem, size, grid, settings.cpu_seconds);
      const auto [err_opencl, err_cpu] = errors_against_tight(problem, size, grid, cpu);
      const double flops_all_runs = static_cast<double>(stats.point_evaluations) * pairs * 4.0 * settings.runs;
      std::printf("%5d %6d | %9.3f %8.2f %8.1f | %9.1f %5.1f%% %5.1f%% | %6.0f%% %8.1f | %9.1f %5d %7.1fx | %9.2e "
                  "%9.2e %9.2e | "
                  "%7.2f\n",
                  n, size, t, pixels / t / 1e6, static_cast<double>(stats.point_evaluations) / pixels, gflops,
                  100.0 * gflops / peak_nominal, peak_measured > 0 ? 100.0 * gflops / peak_measured : 0.0,
                  100.0 * cpu_share, flops_all_runs / (cpu_used / machine.cores) / 1e9, cpu.seconds_full, cpu.rows,
                  cpu.seconds_full / t, cpu.max_diff, err_opencl, err_cpu, problem.closest_approach().distance_px);
      std::fflush(stdout);
    }
  }
}

// flow_points_with_jacobian against flow_points on the same ~20 000 points (a 141² lattice of a 1024² square,
// the bench's features for it), for each precision rule: median of `runs` interleaved calls of each, one process.
// 'auto' is the backend's default (flow_points in float32 at tolerance 0.01 px; the Jacobian path in double where
// the device has cl_khr_fp64); 'float' and 'double' force both calls to that kernel.
void run_jacobian_table(const Settings& settings) {
  const int size = 1024;
  const int side = 141;
  std::vector<Point> points;
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) points.emplace_back((i + 0.5) * size / side, (j + 0.5) * size / side);
  }
  std::printf("\nflow_points_with_jacobian / flow_points, %zu points in a %d² square, median of %d runs each:\n",
              points.size(), size, settings.runs);
  std::printf("%5s %7s | %10s %10s | %7s\n", "n", "kernel", "flow s", "jacobian s", "ratio");
  const std::pair<const char*, OpenClPrecision> precisions[] = {{"auto", OpenClPrecision::kAuto},
                                                                {"float", OpenClPrecision::kFloat},
                                                                {"double", OpenClPrecision::kDouble}};
  for (const int n : settings.features) {
    const WarpProblem problem = bench_problem(n, size);
    for (const auto& [label, precision] : precisions) {
      OpenClOptions options;
      options.precision = precision;
      OpenClWarpBackend opencl(options);
      std::vector<FlowJacobian> jacobians(points.size());
      auto flow = [&] {
        std::vector<Point> p = points;
        const auto start = Clock::now();
        opencl.flow_points(problem, p, Direction::kInverse, {});
        return seconds_since(start);
      };
      auto flow_with_jacobian = [&] {
        std::vector<Point> p = points;
        const auto start = Clock::now();
        opencl.flow_points_with_jacobian(problem, p, jacobians, Direction::kInverse, {});
        return seconds_since(start);
      };
      flow();  // program builds out of the timing
      flow_with_jacobian();
      std::vector<double> plain, with_jacobian;
      for (int r = 0; r < settings.runs; ++r) {
        plain.push_back(flow());
        with_jacobian.push_back(flow_with_jacobian());
      }
      const double a = median(plain);
      const double b = median(with_jacobian);
      std::printf("%5d %7s | %10.3f %10.3f | %6.2fx\n", n, label, a, b, b / a);
      std::fflush(stdout);
    }
  }
}

// A 1024² RGB test texture (smooth bands and a grid), values in [0, 1].
Image test_texture(int size) {
  Image image(size, size, 3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      float* p = image.pixel(x, y);
      p[0] = static_cast<float>(0.5 + 0.5 * std::sin(0.05 * x) * std::cos(0.04 * y));
      p[1] = ((x / 32 + y / 32) % 2) ? 0.9f : 0.1f;
      p[2] = static_cast<float>(x) / static_cast<float>(size - 1);
    }
  }
  return image;
}

void run_tps_comparison(int runs) {
  const int size = 1024;
  const int n = 50;
  const WarpProblem problem = bench_problem(n, size);
  const Image source = test_texture(size);
  std::printf("\nImage warp, %d², %d features (same features and texture; median of %d runs):\n", size, n, runs);
  OpenClWarpBackend opencl;
  for (const bool exact : {true, false}) {
    ImageWarpOptions options;
    options.exact = exact;
    warp_image(opencl, problem, source, options);  // warm-up
    std::vector<double> times;
    for (int r = 0; r < runs; ++r) {
      const auto start = Clock::now();
      warp_image(opencl, problem, source, options);
      times.push_back(seconds_since(start));
    }
    std::printf("  texwarp OpenCL, %s: %.3f s\n",
                exact ? "exact (a pathline per pixel, bilinear)" : "certified lattice (default, 0.05 px, bilinear)",
                median(times));
  }
#if defined(TEXWARP_BENCH_HAVE_OPENCV)
  cv::Mat src(size, size, CV_8UC3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const float* p = source.pixel(x, y);
      src.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uchar>(255 * p[2]), static_cast<uchar>(255 * p[1]), static_cast<uchar>(255 * p[0]));
    }
  }
  std::vector<cv::Point2f> from, to;
  std::vector<cv::DMatch> matches;
  for (std::size_t i = 0; i < problem.features().size(); ++i) {
    const Feature& f = problem.features()[i];
    from.emplace_back(static_cast<float>(f.source.real()), static_cast<float>(f.source.imag()));
    to.emplace_back(static_cast<float>(f.target.real()), static_cast<float>(f.target.imag()));
    matches.emplace_back(static_cast<int>(i), static_cast<int>(i), 0.0f);
  }
  std::vector<double> times;
  for (int r = 0; r < runs + 1; ++r) {
    const auto start = Clock::now();
    cv::Ptr<cv::ThinPlateSplineShapeTransformer> tps = cv::createThinPlateSplineShapeTransformer();
    tps->estimateTransformation(to, from, matches);  // warpImage pulls: target shape first
    cv::Mat out;
    tps->warpImage(src, out);
    if (r > 0) times.push_back(seconds_since(start));
  }
  std::printf("  OpenCV thin-plate spline (estimateTransformation + warpImage, 8-bit RGB, bilinear): %.3f s\n",
              median(times));
#else
  std::printf("  OpenCV thin-plate spline: not built (OpenCV shape module not found)\n");
#endif
}

}  // namespace
}  // namespace texwarp::bench

int main(int argc, char** argv) {
  using namespace texwarp::bench;
  Settings settings;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--features") {
      settings.features = parse_list(value());
    } else if (arg == "--sizes") {
      settings.sizes = parse_list(value());
    } else if (arg == "--runs") {
      settings.runs = std::max(1, std::stoi(value()));
    } else if (arg == "--cpu-seconds") {
      settings.cpu_seconds = std::stod(value());
    } else if (arg == "--no-tps") {
      settings.tps = false;
    } else if (arg == "--quick") {
      settings.sizes = {512, 1024};
    } else if (arg == "--jacobian") {
      settings.jacobian = true;
    } else {
      std::fprintf(stderr,
                   "usage: %s [--features 10,50,100,200] [--sizes 512,1024,2048] [--runs 5] [--cpu-seconds 15] "
                   "[--no-tps] [--quick] [--jacobian]\n",
                   argv[0]);
      return 2;
    }
  }
  try {
    texwarp::OpenClWarpBackend probe;
    if (settings.jacobian) {
      std::printf("OpenCL device: %s; load average at start: %s\n", probe.device_description().c_str(),
                  load_average().c_str());
      run_jacobian_table(settings);
      std::printf("\nload average at end: %s\n", load_average().c_str());
      return 0;
    }
    const MachinePeak machine = measure_machine_peak();
    std::printf("load average at start: %s\n", load_average().c_str());
    print_machine(machine, probe.device_description());
    run_table(settings, machine);
    if (settings.tps) run_tps_comparison(settings.runs);
    std::printf("\nload average at end: %s\n", load_average().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "texwarp_bench_kernels: %s\n", e.what());
    return 1;
  }
  return 0;
}
