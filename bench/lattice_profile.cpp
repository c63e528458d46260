// Where the certified lattice's work goes on one feature file (issue 15): per level, cells checked, failed (error
// or fold), split or sent to their pixels' own pathlines, pathlines (plain, with Jacobian), their wall time and
// field evaluations per point on the OpenCL backend; beside it the exact per-pixel path. Figures, not pass/fail.
//
// Usage: texwarp_bench_lattice_profile FEATURES.json SIZE [--no-exact] [--batches] [--lockstep ITEMS]
//                                      [--measure TOLERANCE]
//        (FEATURES.json: the CLI's feature file, id, source, target; --batches: every pathline batch's figures;
//        --lockstep: each batch's points also integrated alone by the CPU reference on ITEMS work-items;
//        --measure: every pixel of the lattice against the exact path integrated to TOLERANCE px, beside the
//        certificate: its estimate (check points and edges), the bound, and the measured worst over the estimate)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "kernel_contract.hpp"
#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/pathline.hpp"
#include "texwarp/core/spatial_order.hpp"
#include "texwarp/core/velocity_field.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace {

using namespace texwarp;

std::vector<Feature> read_features(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  const nlohmann::json doc = nlohmann::json::parse(in);
  std::vector<Feature> out;
  for (const auto& f : doc.at("features")) {
    const auto& s = f.at("source");
    const auto& t = f.at("target");
    out.push_back({f.at("id").get<std::string>(), Point(s.at(0).get<double>(), s.at(1).get<double>()),
                   Point(t.at(0).get<double>(), t.at(1).get<double>())});
  }
  return out;
}

// The OpenCL backend's grouping of a batch: Morton order of the points (core's spatial_order), kPointsPerItem
// consecutive points per work-item (kernels' contract).
constexpr std::size_t kPointsPerItem = kernels_detail::kPointsPerItem;

// Lockstep waste of a batch: for `items` work-items spread over it, every point integrated alone by the CPU
// reference (its own step sequence); the work-item runs as many evaluations as its hardest point needs.
void print_lockstep(const WarpProblem& problem, std::size_t segment, std::span<const Point> points, bool jacobian,
                    std::size_t items, bool in_item_order = false) {
  std::vector<std::size_t> order = spatial_order(points);
  if (in_item_order) std::iota(order.begin(), order.end(), std::size_t{0});
  const std::size_t total_items = (points.size() + kPointsPerItem - 1) / kPointsPerItem;
  const VelocityField field(problem, segment);
  double sum = 0.0, sum_max = 0.0, lo = INFINITY, hi = 0.0, steps = 0.0, rejected = 0.0;
  std::size_t counted = 0, counted_items = 0;
  for (std::size_t k = 0; k < std::min(items, total_items); ++k) {
    const std::size_t item = k * total_items / std::min(items, total_items);
    double item_max = 0.0;
    for (std::size_t i = item * kPointsPerItem; i < std::min(points.size(), (item + 1) * kPointsPerItem); ++i) {
      Point p = points[order[i]];
      FlowJacobian j;
      const IntegrationStats st =
          jacobian ? integrate_pathlines(field, std::span<Point>(&p, 1), std::span<FlowJacobian>(&j, 1),
                                         Direction::kInverse, problem.pathline_tolerance_px(Direction::kInverse))
                   : integrate_pathlines(field, std::span<Point>(&p, 1), Direction::kInverse,
                                         problem.pathline_tolerance_px(Direction::kInverse));
      const auto e = static_cast<double>(st.evaluations);
      sum += e;
      steps += static_cast<double>(st.steps);
      rejected += static_cast<double>(st.rejected);
      item_max = std::max(item_max, e);
      lo = std::min(lo, e);
      hi = std::max(hi, e);
      ++counted;
    }
    sum_max += item_max;
    ++counted_items;
  }
  if (counted == 0) return;
  const double mean = sum / static_cast<double>(counted);
  const double mean_max = sum_max / static_cast<double>(counted_items);
  std::printf("    alone (CPU, %zu work-items): mean %.1f evaluations/point (range %.0f–%.0f; %.1f steps, %.1f "
              "rejected), work-item max %.1f: lockstep ×%.2f\n",
              counted_items, mean, lo, hi, steps / static_cast<double>(counted),
              rejected / static_cast<double>(counted), mean_max, mean_max / mean);
}

// The OpenCL backend, counting the field evaluations of every batch it integrates.
class CountingBackend final : public WarpBackend {
 public:
  std::string name() const override { return "opencl (counted)"; }
  void flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points, Direction direction,
                    const RunControl& control) override {
    if (lockstep_items > 0) print_lockstep(problem, segment, points, false, lockstep_items);
    inner_.flow_segment(problem, segment, points, direction, control);
    add(false);
  }
  void flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                  std::span<FlowJacobian> jacobians, Direction direction,
                                  const RunControl& control) override {
    if (lockstep_items > 0) print_lockstep(problem, segment, points, true, lockstep_items);
    inner_.flow_segment_with_jacobian(problem, segment, points, jacobians, direction, control);
    add(true);
  }
  std::vector<Point> inverse_map_grid(const WarpProblem& problem, int width, int height,
                                      const RunControl& control) override {
    std::vector<Point> grid = inner_.inverse_map_grid(problem, width, height, control);
    add(false);
    return grid;
  }
  // Points and evaluations since the last call.
  bool verbose = false;            // print every batch
  std::size_t lockstep_items = 0;  // > 0: measure the lockstep waste of every batch on this many work-items
  std::pair<std::size_t, std::size_t> take() {
    const auto out = std::pair{points_, evaluations_};
    points_ = evaluations_ = 0;
    return out;
  }

 private:
  void add(bool jacobian) {
    const OpenClRunStats s = inner_.last_run_stats();
    if (verbose)
      std::printf("  batch: %zu points%s%s, %.1f evaluations/point, %.3f s, %.1f us/point\n", s.points,
                  jacobian ? " with Jacobian" : "",
                  s.retried_in_double  ? " (float32's steps collapsed: again in double)"
                  : s.double_precision ? " (double)"
                                       : "",
                  s.points ? double(s.point_evaluations) / double(s.points) : 0.0, s.seconds,
                  s.points ? 1e6 * s.seconds / double(s.points) : 0.0);
    points_ += s.points;
    evaluations_ += s.point_evaluations;
  }
  OpenClWarpBackend inner_;
  std::size_t points_ = 0;
  std::size_t evaluations_ = 0;
};

double per_point(std::pair<std::size_t, std::size_t> pe) {
  return pe.first == 0 ? 0.0 : static_cast<double>(pe.second) / static_cast<double>(pe.first);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s FEATURES.json SIZE [--no-exact]\n", argv[0]);
    return 2;
  }
  const int size = std::stoi(argv[2]);
  bool with_exact = true;
  bool batches = false;
  std::size_t lockstep = 0;
  double measure_tolerance = 0.0;
  for (int i = 3; i < argc; ++i) {
    if (std::strcmp(argv[i], "--no-exact") == 0) with_exact = false;
    if (std::strcmp(argv[i], "--batches") == 0) batches = true;
    if (std::strcmp(argv[i], "--lockstep") == 0 && i + 1 < argc) lockstep = std::stoul(argv[++i]);
    if (std::strcmp(argv[i], "--measure") == 0 && i + 1 < argc) measure_tolerance = std::stod(argv[++i]);
  }
  const WarpProblem problem(read_features(argv[1]), WarpOptions{});
  CountingBackend backend;
  std::vector<Point> warm = {Point(1.5, 1.5)};
  map_points(backend, problem, warm, Direction::kInverse);  // kernels built before anything is timed
  backend.take();
  backend.verbose = batches || lockstep > 0;
  backend.lockstep_items = lockstep;

  LatticeProfile profile;
  CertifiedGridOptions options;
  options.profile = &profile;
  WarpCertificate cert;
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Point> grid = certified_inverse_map_grid(backend, problem, size, size, options, {}, cert);
  const double lattice_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double evals = per_point(backend.take());
  std::printf("%s %d²: lattice %.2f s, %zu pathlines (%zu with Jacobian), %zu pixel pathlines, bound %.4f px%s, "
              "%.1f evaluations/point\n",
              argv[1], size, lattice_s, cert.pathlines, cert.jacobian_pathlines, cert.pixel_pathlines,
              cert.max_error_px_bound, profile.exact ? " (fell back to exact)" : "", evals);
  std::printf(
      "| cell px | cells | accepted at once | quarter points | failed: error | fold | split | to pixels | plain "
      "| with J | seconds |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const LatticeLevel& l : profile.levels) {
    std::printf("| %d | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %zu | %.2f |\n", l.cell_px, l.cells,
                l.quick_accepted, l.quarter_checked, l.failed_error, l.failed_fold, l.split, l.to_pixels,
                l.plain_pathlines, l.jacobian_pathlines, l.seconds);
  }
  std::printf("failed 8 px cells on their 2 px grid: %zu, %zu accepted (%zu at once), %zu pathlines, %.2f s\n",
              profile.fine_cells, profile.fine_accepted, profile.fine_quick_accepted, profile.fine_pathlines,
              profile.fine_seconds);
  std::printf("pixels of unsplit failed cells: %zu pathlines, %.2f s; sample: %zu pathlines, %.2f s\n",
              profile.pixel_pathlines, profile.pixel_seconds, profile.sample_pathlines, profile.sample_seconds);
  if (measure_tolerance > 0.0) {
    const std::vector<Point> exact =
        backend.inverse_map_grid(problem.with_tolerance(measure_tolerance), size, size, {});
    backend.take();
    double worst = 0.0;
    std::size_t at = 0;  // the worst pixel
    for (std::size_t k = 0; k < grid.size(); ++k) {
      const double e = std::abs(grid[k] - exact[k]);
      if (e > worst) worst = e, at = k;
    }
    std::printf("every pixel against the exact path at %g px: worst %.4f px (± %g) at pixel (%zu, %zu), "
                "estimated %.4f px (ratio %.2f), bound %.4f px, sampled %.4f px\n",
                measure_tolerance, worst, measure_tolerance, at % static_cast<std::size_t>(size),
                at / static_cast<std::size_t>(size), cert.max_error_px_estimated,
                cert.max_error_px_estimated > 0 ? worst / cert.max_error_px_estimated : 0.0, cert.max_error_px_bound,
                cert.max_error_px_sampled);
  }
  if (with_exact) {
    const auto exact_start = std::chrono::steady_clock::now();
    backend.inverse_map_grid(problem, size, size, {});
    const double exact_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - exact_start).count();
    std::printf("exact: %.2f s, %d pathlines, %.1f evaluations/point\n", exact_s, size * size,
                per_point(backend.take()));
    if (lockstep > 0) {
      // The grid kernel's work-items: blocks of 16×4 pixels.
      std::vector<Point> blocks;
      const int bx = size / 16, by = size / 4;
      for (std::size_t k = 0; k < lockstep; ++k) {
        const std::size_t b = k * static_cast<std::size_t>(bx * by) / lockstep;
        const int x0 = static_cast<int>(b % static_cast<std::size_t>(bx)) * 16;
        const int y0 = static_cast<int>(b / static_cast<std::size_t>(bx)) * 4;
        for (int y = y0; y < y0 + 4; ++y) {
          for (int x = x0; x < x0 + 16; ++x) blocks.emplace_back(x + 0.5, y + 0.5);
        }
      }
      print_lockstep(problem, problem.segments().size() - 1, blocks, false, lockstep, true);
    }
  }
  return 0;
}
