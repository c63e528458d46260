// Benchmark of the certified fast warp (issue 5): for n features and square outputs, the lattice path's median
// time, pathlines, certificate and measured error, against the exact per-pixel path in the same run; and
// 1024² warps beside OpenCV's thin-plate-spline warp of the same input. Figures, not pass/fail.
//
// Usage: texwarp_bench_certified [--quick] [--backend cpu|opencl] [--set smooth|independent] [--only N SIZE]
//                                [--tps] (only the side-by-side with OpenCV)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>
#include <opencv2/shape/shape_transformer.hpp>

#include "texwarp/core/baseline_warp.hpp"
#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/kernels/opencl_backend.hpp"

namespace {

using namespace texwarp;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Feature k of n on a jittered grid over the middle 80 % of a size×size image (two draws from rng).
Point jittered_grid_point(int k, int n, int size, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
  const double spacing = (size - 0.2 * size) / std::max(1, side - 1);
  const int column = k % side;
  const int row = k / side;
  return Point(0.1 * size + column * spacing + 0.2 * spacing * unit(rng),
               0.1 * size + row * spacing + 0.2 * spacing * unit(rng));
}

// n features on the jittered grid, each displaced on its own by up to 4 % of the size, drawn until the set is
// valid (no collisions). Neighbours may move toward each other by twice that: the stress case, with
// near-collisions and the inverse map stretching areas by up to ~80×.
std::vector<Feature> independent_features(int n, int size, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::vector<Feature> f;
    for (int k = 0; k < n; ++k) {
      const Point p = jittered_grid_point(k, n, size, rng);
      f.push_back({"f" + std::to_string(k), p, p + 0.04 * size * Point(unit(rng), unit(rng))});
    }
    try {
      WarpProblem check(f, {});
      return f;
    } catch (const std::exception&) {
    }
  }
  throw std::runtime_error("no valid feature set");
}

// n features on the jittered grid, displaced by a smooth random field (eight Gaussian bumps of width a fifth of
// the image) scaled so the largest displacement is 4 % of the size: neighbours move together, as the features of
// a texture do when they follow a mesh's flattening.
std::vector<Feature> smooth_features(int n, int size, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Point> centres;
  std::vector<Point> amplitudes;
  for (int k = 0; k < 8; ++k) {
    centres.emplace_back(0.5 * size * (1.0 + unit(rng)), 0.5 * size * (1.0 + unit(rng)));
    amplitudes.emplace_back(unit(rng), unit(rng));
  }
  const double sigma = 0.2 * size;
  auto field = [&](Point p) {
    Point d(0.0);
    for (int k = 0; k < 8; ++k) d += amplitudes[k] * std::exp(-std::norm(p - centres[k]) / (2.0 * sigma * sigma));
    return d;
  };
  std::vector<Point> sources;
  std::vector<Point> displacements;
  double largest = 0.0;
  for (int k = 0; k < n; ++k) {
    sources.push_back(jittered_grid_point(k, n, size, rng));
    displacements.push_back(field(sources.back()));
    largest = std::max(largest, std::abs(displacements.back()));
  }
  std::vector<Feature> f;
  f.reserve(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    f.push_back({"f" + std::to_string(k), sources[k], sources[k] + (0.04 * size / largest) * displacements[k]});
  }
  WarpProblem check(f, {});
  return f;
}

std::vector<Feature> make_features(const std::string& set, int n, int size, std::uint32_t seed) {
  return set == "smooth" ? smooth_features(n, size, seed) : independent_features(n, size, seed);
}

// Max |lattice − pathline| on random pixels, the pathlines by the CPU reference at a tight tolerance.
double measured_error(const WarpProblem& problem, const std::vector<Point>& grid, int size, std::size_t samples) {
  WarpOptions tight = problem.options();
  tight.tolerance_px = 1e-4;
  const WarpProblem reference(problem.features(), tight);
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::size_t> pick(0, grid.size() - 1);
  std::vector<std::size_t> idx;
  std::vector<Point> pts;
  for (std::size_t k = 0; k < samples; ++k) {
    idx.push_back(pick(rng));
    const std::size_t column = idx.back() % size;
    const std::size_t row = idx.back() / size;
    pts.emplace_back(static_cast<double>(column) + 0.5, static_cast<double>(row) + 0.5);
  }
  CpuBackend cpu;
  map_points(cpu, reference, pts, Direction::kInverse);
  double worst = 0.0;
  for (std::size_t k = 0; k < pts.size(); ++k) worst = std::max(worst, std::abs(pts[k] - grid[idx[k]]));
  return worst;
}

// Exact path time: all pixels when affordable, else `rows` rows spread over the image, scaled to the whole.
std::pair<double, bool> exact_seconds(WarpBackend& backend, const WarpProblem& problem, int size, int rows) {
  if (rows >= size) {
    const auto t = Clock::now();
    backend.inverse_map_grid(problem, size, size, {});
    return {seconds_since(t), false};
  }
  std::vector<Point> pts;
  for (int r = 0; r < rows; ++r) {
    const int y = r * size / rows;
    for (int x = 0; x < size; ++x) pts.emplace_back(x + 0.5, y + 0.5);
  }
  const auto t = Clock::now();
  map_points(backend, problem, pts, Direction::kInverse);
  return {seconds_since(t) * size / rows, true};
}

Image pattern_image(int size) {
  Image img(size, size, 3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      float* p = img.pixel(x, y);
      p[0] = static_cast<float>(((x / 32 + y / 32) % 2) * 0.8 + 0.1);
      p[1] = static_cast<float>(x) / static_cast<float>(size);
      p[2] = static_cast<float>(y) / static_cast<float>(size);
    }
  }
  return img;
}

// OpenCV's thin-plate-spline warp of the same image with the same features (the tool users reach for).
double opencv_tps_seconds(const std::vector<Feature>& features, int size, int runs) {
  cv::Mat src(size, size, CV_8UC3);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) src.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(x), static_cast<uchar>(y), 0);
  }
  std::vector<cv::Point2f> from;
  std::vector<cv::Point2f> to;
  std::vector<cv::DMatch> matches;
  for (std::size_t i = 0; i < features.size(); ++i) {
    from.emplace_back(static_cast<float>(features[i].source.real()), static_cast<float>(features[i].source.imag()));
    to.emplace_back(static_cast<float>(features[i].target.real()), static_cast<float>(features[i].target.imag()));
    matches.emplace_back(static_cast<int>(i), static_cast<int>(i), 0.0f);
  }
  std::vector<double> times;
  for (int r = 0; r < runs; ++r) {
    const auto t = Clock::now();
    auto tps = cv::createThinPlateSplineShapeTransformer(0.0);
    // OpenCV's warpImage pulls pixels through the estimated map: estimate target → source.
    tps->estimateTransformation(cv::Mat(to).reshape(2, 1), cv::Mat(from).reshape(2, 1), matches);
    cv::Mat dst;
    tps->warpImage(src, dst, cv::INTER_LINEAR);
    times.push_back(seconds_since(t));
  }
  return median(times);
}

int run(int argc, char** argv) {
  bool quick = false;
  bool side_by_side_only = false;
  int only_n = 0;
  int only_size = 0;
  std::string backend_name = "opencl";
  std::vector<std::string> sets = {"smooth", "independent"};
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) quick = true;
    if (std::strcmp(argv[i], "--tps") == 0) side_by_side_only = true;
    if (std::strcmp(argv[i], "--backend") == 0 && i + 1 < argc) backend_name = argv[++i];
    if (std::strcmp(argv[i], "--set") == 0 && i + 1 < argc) sets = {argv[++i]};
    if (std::strcmp(argv[i], "--only") == 0 && i + 2 < argc) {
      only_n = std::atoi(argv[++i]);
      only_size = std::atoi(argv[++i]);
    }
  }
  std::unique_ptr<WarpBackend> backend;
  if (backend_name == "opencl") backend = make_opencl_backend();
  if (!backend) backend = std::make_unique<CpuBackend>();
  std::printf("certified warp benchmark on backend %s; tolerance 0.05 px; medians of %s runs\n"
              "sets: smooth = neighbours move together (a smooth displacement field sampled at the features); "
              "independent = each feature displaced on its own (near-collisions)\n\n",
              backend->name().c_str(), quick ? "3" : "3 (2048²) or 5");

  if (!side_by_side_only) {
    std::printf("| set | n | output | fast (s) | pathlines | with Jacobian | pathlines/pixel | sampled err (px) | "
                "measured err (px) | min det J | exact (s) | speed-up |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::vector<int> counts = quick ? std::vector<int>{10, 50} : std::vector<int>{10, 50, 100, 200};
    std::vector<int> sizes = quick ? std::vector<int>{512} : std::vector<int>{512, 1024, 2048};
    if (only_n > 0) {
      counts = {only_n};
      sizes = {only_size};
    }
    for (const std::string& set : sets) {
      for (const int n : counts) {
        for (const int size : sizes) {
          const WarpProblem problem(make_features(set, n, size, static_cast<std::uint32_t>(n)), {});
          CertifiedGridOptions options;
          WarpCertificate cert;
          std::vector<double> times;
          std::vector<Point> grid;
          const int runs = (quick || size >= 2048) ? 3 : 5;
          for (int r = 0; r < runs; ++r) {
            const auto t = Clock::now();
            grid = certified_inverse_map_grid(*backend, problem, size, size, options, {}, cert);
            times.push_back(seconds_since(t));
          }
          const double fast = median(times);
          const double err = measured_error(problem, grid, size, 300);
          const int rows = size <= 512 && n <= 50 ? size : std::max(8, 2048 * 16 / (size * std::max(1, n / 25)));
          const auto [exact, extrapolated] = exact_seconds(*backend, problem, size, std::min(rows, size));
          std::printf("| %s | %d | %d² | %.3f | %zu | %zu | %.4f | %.4f | %.4f | %.3f | %.2f%s | %.1f× |\n",
                      set.c_str(), n, size, fast, cert.pathlines, cert.jacobian_pathlines,
                      static_cast<double>(cert.pathlines) / (static_cast<double>(size) * size),
                      cert.max_error_px_sampled, err, cert.min_jacobian_det, exact, extrapolated ? " (rows)" : "",
                      exact / fast);
          std::fflush(stdout);
        }
      }
    }
    if (only_n > 0) return 0;
  }

  // The two warps alternate run by run, so that both see the same machine load.
  const int runs = quick ? 3 : 5;
  std::printf("\nWhole warp of a 1024² RGB image (certified lattice + bilinear resampling) beside OpenCV's TPS warp "
              "of the same image with the same features, alternating, medians of %d:\n\n"
              "| set | n | texwarp warp (s) | OpenCV TPS warp (s) | ratio TPS/texwarp | texwarp min det J | "
              "TPS folded (det J ≤ 0, of 128² sampled pixels) |\n|---|---|---|---|---|---|---|\n",
              runs);
  const Image image = pattern_image(1024);
  for (const std::string& set : sets) {
    for (const int n : {50, 200}) {
      const auto features = make_features(set, n, 1024, static_cast<std::uint32_t>(1000 + n));
      const WarpProblem problem(features, {});
      std::vector<double> ours;
      std::vector<double> tps;
      WarpCertificate cert;
      for (int r = 0; r < runs; ++r) {
        const auto t = Clock::now();
        ImageWarpOptions o;
        o.border = Border::kClamp;
        warp_image(*backend, problem, image, o, {}, &cert);
        ours.push_back(seconds_since(t));
        tps.push_back(opencv_tps_seconds(features, 1024, 1));
      }
      // The thin-plate spline's inverse map (Bookstein's, as OpenCV's) at a 128² grid of pixel centres.
      const auto tps_inverse = baseline_map(WarpMethod::kThinPlateSpline, problem, true);
      std::vector<Point> centres;
      for (int y = 0; y < 1024; y += 8) {
        for (int x = 0; x < 1024; x += 8) centres.emplace_back(x + 4.5, y + 4.5);
      }
      const JacobianStats folds = summarize_determinants(jacobian_determinants(
          [&](std::vector<Point>& pts) {
            for (Point& p : pts) p = tps_inverse(p);
          },
          centres, kJacobianStepPx));
      std::printf("| %s | %d | %.3f | %.3f | %.2f | %.3f | %zu |\n", set.c_str(), n, median(ours), median(tps),
                  median(tps) / median(ours), cert.min_jacobian_det, folds.nonpositive);
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "texwarp_bench_certified: %s\n", e.what());
    return 1;
  }
}
