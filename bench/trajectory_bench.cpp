// Benchmark of planned trajectories (issue 13): generated crossing sets of 10, 50 and 200 features in 1024²
// (neighbours swapping places, clusters turned by 180°; only sets whose straight trajectories collide, i.e. that
// were refused before planning): success rate, time to plan (median, p90), methods chosen, the planner's
// distortion proxy and the measured distortion (σ1/σ2, min det J of the inverse map on a grid) per method; and
// the certified lattice warp's time at 1024² on a few sets per size against straight sets of the same size, run
// side by side. Figures, not pass/fail.
//
// Usage: texwarp_bench_trajectory [--sets N] [--warp-sets M] [--distortion-sets D] [--backend cpu|opencl]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "crossing_features.hpp"
#include "random_features.hpp"
#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/kernels/opencl_backend.hpp"
#include "texwarp/proto/enum_names.hpp"

namespace {

using namespace texwarp;
using Clock = std::chrono::steady_clock;

constexpr double kSize = 1024.0;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

struct Distortion {
  double max_ratio = 1.0;
  double mean_ratio = 0.0;
  double min_det = 0.0;
};

// σ1/σ2 and det of the inverse map's Jacobian (variational equation, CPU) on a 16 × 16 grid over the image.
Distortion measure(const WarpProblem& problem) {
  CpuBackend cpu;
  std::vector<Point> grid;
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 16; ++x) grid.emplace_back((x + 0.5) * kSize / 16, (y + 0.5) * kSize / 16);
  }
  std::vector<FlowJacobian> j(grid.size());
  map_points_with_jacobian(cpu, problem, grid, j, Direction::kInverse);
  Distortion d;
  d.min_det = 1e300;
  for (const FlowJacobian& x : j) {
    const double r = singular_value_ratio(x);
    d.max_ratio = std::max(d.max_ratio, r);
    d.mean_ratio += r / static_cast<double>(j.size());
    d.min_det = std::min(d.min_det, x.det());
  }
  return d;
}

double warp_seconds(WarpBackend& backend, const WarpProblem& problem) {
  WarpCertificate certificate;
  const auto start = Clock::now();
  certified_inverse_map_grid(backend, problem, static_cast<int>(kSize), static_cast<int>(kSize), {}, {}, certificate);
  return seconds_since(start);
}

}  // namespace

int main(int argc, char** argv) {
  int sets = 50;
  int warp_sets = 3;
  int distortion_sets = 10;
  std::string backend_name = "opencl";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--sets")) sets = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--warp-sets")) warp_sets = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--distortion-sets")) distortion_sets = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--backend")) backend_name = argv[i + 1];
  }
  std::unique_ptr<WarpBackend> backend =
      backend_name == "cpu" ? std::unique_ptr<WarpBackend>(std::make_unique<CpuBackend>()) : make_opencl_backend();
  std::printf("# trajectory planning on crossing sets in %g², min separation 0.5 px, prealign similarity\n", kSize);
  std::printf("| n | sets (drawn) | success | plan median ms | plan p90 ms | straight-set prepare median ms | methods |"
              " segments median |\n|---|---|---|---|---|---|---|---|\n");
  struct Row {
    std::string method;
    double proxy;
    Distortion d;
  };
  std::vector<std::string> warp_lines;
  std::vector<std::string> distortion_lines;
  for (const int n : {10, 50, 200}) {
    std::vector<double> plan_ms;
    std::vector<double> straight_ms;
    std::vector<double> segments;
    std::map<std::string, int> methods;
    std::vector<std::vector<Feature>> accepted;
    int drawn = 0;
    int failures = 0;
    for (std::uint32_t seed = 1; static_cast<int>(accepted.size()) < sets && drawn < 20 * sets; ++seed) {
      ++drawn;
      auto features = testing::random_crossing_features(n, kSize, seed, seed % 2 == 0);
      try {
        const auto start = Clock::now();
        const WarpProblem problem(features, {});
        const double ms = 1e3 * seconds_since(start);
        if (!problem.trajectory_plan().straight_collides) continue;  // not refused before
        plan_ms.push_back(ms);
        segments.push_back(static_cast<double>(problem.segments().size()));
        ++methods[proto::to_string(problem.trajectory_plan().method)];
        accepted.push_back(std::move(features));
      } catch (const std::exception& e) {
        ++failures;
        accepted.push_back(std::move(features));
        std::fprintf(stderr, "n=%d seed %u: %s\n", n, seed, e.what());
      }
    }
    // The same size straight: valid random sets (prepare includes the collision check of the straight lines).
    for (int s = 0; s < 20; ++s) {
      testing::RandomFeatureSpec spec;
      spec.count = n;
      spec.width = spec.height = kSize;
      spec.seed = static_cast<std::uint32_t>(100 + s);
      const auto f = testing::random_features(spec, {});
      const auto start = Clock::now();
      const WarpProblem problem(f, {});
      straight_ms.push_back(1e3 * seconds_since(start));
    }
    std::string m;
    for (const auto& [name, count] : methods) m += name + " " + std::to_string(count) + " ";
    std::printf("| %d | %zu (%d) | %zu/%zu | %.2f | %.2f | %.2f | %s| %.0f |\n", n, accepted.size(), drawn,
                accepted.size() - failures, accepted.size(), quantile(plan_ms, 0.5), quantile(plan_ms, 0.9),
                quantile(straight_ms, 0.5), m.c_str(), quantile(segments, 0.5));
    std::fflush(stdout);

    // Distortion per method on the first sets.
    std::map<std::string, std::vector<Row>> rows;
    for (int s = 0; s < std::min<int>(distortion_sets, static_cast<int>(accepted.size())); ++s) {
      WarpOptions o;
      o.tolerance_px = 1e-3;
      const WarpProblem problem(accepted[s], o);
      const std::string method = proto::to_string(problem.trajectory_plan().method);
      rows[method].push_back({method, problem.trajectory_plan().distortion, measure(problem)});
    }
    for (const auto& [method, list] : rows) {
      std::vector<double> proxy, max_ratio, mean_ratio, min_det;
      for (const Row& r : list) {
        proxy.push_back(r.proxy);
        max_ratio.push_back(r.d.max_ratio);
        mean_ratio.push_back(r.d.mean_ratio);
        min_det.push_back(r.d.min_det);
      }
      char line[256];
      std::snprintf(line, sizeof line, "| %d | %s | %zu | %.3g | %.3g | %.3g | %.3g | %.3g |", n, method.c_str(),
                    list.size(), quantile(proxy, 0.5), quantile(max_ratio, 0.5), quantile(max_ratio, 1.0),
                    quantile(mean_ratio, 0.5), *std::min_element(min_det.begin(), min_det.end()));
      distortion_lines.emplace_back(line);
      std::fprintf(stderr, "distortion %s\n", line);  // as it comes: long runs may be cut short
    }

    // Warp time at 1024², crossing vs straight sets of the same size, alternating.
    std::vector<double> crossing_s;
    std::vector<double> straight_s;
    for (int s = 0; s < std::min<int>(warp_sets, static_cast<int>(accepted.size())); ++s) {
      crossing_s.push_back(warp_seconds(*backend, WarpProblem(accepted[s], {})));
      testing::RandomFeatureSpec spec;
      spec.count = n;
      spec.width = spec.height = kSize;
      spec.seed = static_cast<std::uint32_t>(100 + s);
      straight_s.push_back(warp_seconds(*backend, WarpProblem(testing::random_features(spec, {}), {})));
    }
    char line[256];
    std::snprintf(line, sizeof line, "| %d | %zu | %.2f | %.2f | %.2f |", n, crossing_s.size(),
                  quantile(crossing_s, 0.5), quantile(straight_s, 0.5),
                  quantile(crossing_s, 0.5) / quantile(straight_s, 0.5));
    warp_lines.emplace_back(line);
    std::fprintf(stderr, "warp %s\n", line);
  }
  std::printf("\n# distortion per method (first sets per size; proxy = planner's Σ_k max |ΔD|/d; σ1/σ2 and det of "
              "the inverse map on a 16² grid, CPU variational equation)\n");
  std::printf("| n | method | sets | proxy median | max σ1/σ2 median | max σ1/σ2 worst | mean σ1/σ2 median |"
              " min det J |\n|---|---|---|---|---|---|---|---|\n");
  for (const auto& l : distortion_lines) std::printf("%s\n", l.c_str());
  std::printf("\n# certified lattice warp at 1024², default options, backend %s (median seconds)\n",
              backend->name().c_str());
  std::printf("| n | sets | crossing s | straight s | ratio |\n|---|---|---|---|---|\n");
  for (const auto& l : warp_lines) std::printf("%s\n", l.c_str());
  return 0;
}
