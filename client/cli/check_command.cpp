// `texwarp check`: validates a feature file and reports, as JSON: the planned trajectories and their closest
// approach, constraint residuals, gradient-feature Jacobians, Jacobian-determinant statistics and distortion of
// the map over the output grid.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <numbers>

#include "backend_choice.hpp"
#include "cli_command.hpp"
#include "command_clock.hpp"
#include "feature_file.hpp"
#include "texwarp/core/baseline_warp.hpp"
#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/warp_problem_report.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_report_codec.hpp"

namespace texwarp::cli {
namespace {

constexpr int kDefaultMaxGridSide = 128;         // grid nodes per side unless --grid-step says otherwise
constexpr long long kMaxGridPoints = 1LL << 24;  // each a double-precision pathline with its Jacobian
constexpr double kGradientTolerancePx = 1e-10;   // gradient features' Jacobians: tight, few points
constexpr double kGradientStepPx = 1e-4;

struct CheckArgs {
  std::string features;
  int width = 0;
  int height = 0;
  int grid_step = 0;
  std::string method = "field";
  bool mirror = false;
  bool trajectories = false;
  bool progress = false;
  std::string timings;  // "", "table" or "json"
  BackendChoice backend;
};

double degrees(double radians) { return radians * 180.0 / std::numbers::pi; }

// Maps points in place in a direction: the method's map (the vector field's, or a baseline's).
using PointMap = std::function<void(std::vector<Point>&, Direction)>;

// Measured complex derivative f'(P) of the map at a point by central differences (x direction: for a
// conformal Jacobian this is S·e^{iφ}).
Point measured_derivative(const PointMap& map, Point p) {
  std::vector<Point> pts = {p + kGradientStepPx, p - kGradientStepPx};
  map(pts, Direction::kForward);
  return (pts[0] - pts[1]) / (2.0 * kGradientStepPx);
}

// The texture width the `mirror` option flips about: --width, else the features' extent as the grid takes it.
int mirror_width(const proto::WarpSpec& spec, int width) {
  if (width > 0) return width;
  double max_x = 1.0;
  for (const auto& f : spec.features) max_x = std::max({max_x, f.source[0], f.target[0]});
  return static_cast<int>(std::ceil(max_x)) + 1;
}

void print(const proto::CheckReport& report) { std::cout << proto::encode_check_report(report).dump(2) << "\n"; }

int run_check(const CheckArgs& args) {
  using proto::LatencyStage;
  // The residuals and gradient features are checked first (verify), then the Jacobian grid's pathlines.
  CommandClock clock({LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup, LatencyStage::kVerify,
                      LatencyStage::kPathlines},
                     args.progress);
  const auto plan_start = std::chrono::steady_clock::now();
  proto::CheckReport report;
  std::optional<WarpProblem> loaded;
  try {
    const proto::WarpSpec spec = read_feature_file(args.features);
    const bool mirror = spec.mirror || args.mirror;
    report.mirror = mirror_report(features_from_spec(spec), mirror);
    loaded.emplace(problem_from_spec(spec, args.features, mirror ? mirror_width(spec, args.width) : 0));
  } catch (const InputError& e) {
    report.failure = proto::CheckFailureReport{e.where().str(), e.detail()};
    print(report);
    throw;
  }
  const WarpProblem& problem = *loaded;
  const WarpMethod method = parse_warp_method(args.method, InputLocation::flag("--method"));
  int width = args.width;
  int height = args.height;
  if (width == 0 || height == 0) {
    double max_x = 1.0;
    double max_y = 1.0;
    for (const Feature& f : problem.features()) {
      max_x = std::max({max_x, f.source.real(), f.target.real()});
      max_y = std::max({max_y, f.source.imag(), f.target.imag()});
    }
    if (width == 0) width = static_cast<int>(std::ceil(max_x)) + 1;
    if (height == 0) height = static_cast<int>(std::ceil(max_y)) + 1;
  }

  // In 64 bits: a width near INT_MAX would overflow the rounding up.
  const int step = args.grid_step > 0
                       ? args.grid_step
                       : static_cast<int>(std::max<long long>(
                             1, (std::max<long long>(width, height) + kDefaultMaxGridSide - 1) / kDefaultMaxGridSide));
  const int nx = std::max(2, (width - 1) / step + 1);
  const int ny = std::max(2, (height - 1) / step + 1);
  if (static_cast<long long>(nx) * ny > kMaxGridPoints) {
    throw InputError(InputLocation::flag("--grid-step"),
                     "a Jacobian grid of " + std::to_string(nx) + " × " + std::to_string(ny) + " points over " +
                         std::to_string(width) + " × " + std::to_string(height) + " pixels is more than " +
                         std::to_string(kMaxGridPoints) + " points: use a larger --grid-step");
  }
  std::vector<Point> grid;  // pixel centres every `step` pixels
  grid.reserve(static_cast<std::size_t>(nx) * ny);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) grid.emplace_back(i * step + 0.5, j * step + 0.5);
  }
  // The grid's points carry the variational equation at the tight tolerance (the field's; a baseline's map is
  // closed).
  runner::StageWorkload workload;
  workload.input_pixels = 0.0;
  workload.output_pixels = static_cast<double>(grid.size());
  workload.features = problem.size();
  workload.pathlines = method == WarpMethod::kField;
  workload.exact = true;
  workload.jacobian_grid = method == WarpMethod::kField;
  clock.set_workload(workload);  // known before the device is set up: the weights of every later stage
  clock.add(LatencyStage::kPlan, std::chrono::duration<double>(std::chrono::steady_clock::now() - plan_start).count());
  auto backend = clock.time(LatencyStage::kDeviceSetup, [&] { return make_backend(args.backend); });
  RunControl control;
  control.threads = args.backend.threads;
  // The field's map at the problem's tolerance, and at a tight one for derivatives; a baseline's closed form.
  WarpOptions tight_options = problem.options();
  tight_options.tolerance_px = kGradientTolerancePx;
  const WarpProblem tight(problem.features(), tight_options);
  PointMap map;
  PointMap precise_map;
  if (method == WarpMethod::kField) {
    map = [&](std::vector<Point>& p, Direction d) { map_points(*backend, problem, p, d, control); };
    precise_map = [&](std::vector<Point>& p, Direction d) { map_points(*backend, tight, p, d, control); };
  } else {
    const auto forward = baseline_map(method, problem, false);
    const auto inverse = baseline_map(method, problem, true);
    map = [forward, inverse](std::vector<Point>& p, Direction d) {
      for (Point& q : p) q = d == Direction::kForward ? forward(q) : inverse(q);
    };
    precise_map = map;
  }

  std::size_t positional = 0;
  for (const Feature& f : problem.features()) positional += f.is_gradient() ? 0 : 1;
  report.features = {problem.size(), positional, problem.size() - positional};
  report.options = {problem.alpha(), problem.options().prealign, problem.tolerance_px(),
                    problem.options().min_separation_px};
  report.prealignment = prealignment_report(problem.prealignment());
  report.closest_approach = closest_approach_report(problem);
  report.trajectory = trajectory_report(problem, args.trajectories);

  const auto verify_start = std::chrono::steady_clock::now();
  std::vector<Point> mapped_sources;
  for (const Feature& f : problem.features()) mapped_sources.push_back(f.source);
  map(mapped_sources, Direction::kForward);
  for (std::size_t i = 0; i < mapped_sources.size(); ++i) {
    const double r = std::abs(mapped_sources[i] - problem.features()[i].target);
    report.residuals.max_px = std::max(report.residuals.max_px, r);
    report.residuals.per_feature.push_back({describe_feature(problem.features(), i), std::nullopt, r});
  }

  for (std::size_t i = 0; i < problem.size(); ++i) {
    const Feature& f = problem.features()[i];
    if (!f.is_gradient()) continue;
    const Point measured = measured_derivative(precise_map, f.source);
    const double expected_scale = f.target_frame->scale / f.source_frame->scale;
    const double expected_angle = f.target_frame->angle_rad - f.source_frame->angle_rad;
    const double angle_error = std::remainder(std::arg(measured) - expected_angle, 2.0 * std::numbers::pi);
    report.gradient_features.push_back({describe_feature(problem.features(), i), expected_scale, std::abs(measured),
                                        degrees(std::remainder(expected_angle, 2.0 * std::numbers::pi)),
                                        degrees(angle_error)});
  }

  clock.add(LatencyStage::kVerify,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - verify_start).count());
  control.progress = clock.progress_within(LatencyStage::kPathlines);
  const auto grid_start = std::chrono::steady_clock::now();
  std::vector<double> determinants;
  if (method == WarpMethod::kField) {
    // The distortion from the same Jacobians: σ1/σ2 (max, mean over the grid) and min det J.
    const std::vector<FlowJacobian> jacobians = warp_jacobians(*backend, problem, grid, Direction::kInverse, control);
    proto::DistortionReport& d = report.distortion.emplace();
    d.max_singular_ratio = 1.0;
    d.mean_singular_ratio = 0.0;
    d.min_det = std::numeric_limits<double>::infinity();
    for (const FlowJacobian& j : jacobians) {
      const double ratio = singular_value_ratio(j);
      d.max_singular_ratio = std::max(d.max_singular_ratio, ratio);
      d.mean_singular_ratio += ratio / static_cast<double>(jacobians.size());
      d.min_det = std::min(d.min_det, j.det());
      determinants.push_back(j.det());
    }
  } else {
    determinants =
        jacobian_determinants([&](std::vector<Point>& p) { map(p, Direction::kInverse); }, grid, kJacobianStepPx);
  }
  clock.add(LatencyStage::kPathlines,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - grid_start).count());
  const JacobianStats stats = summarize_determinants(determinants);
  report.jacobian = jacobian_report(stats,
                                    method == WarpMethod::kField ? proto::JacobianEstimate::kVariationalEquation
                                                                 : proto::JacobianEstimate::kCentralDifferences,
                                    step);
  report.jacobian.output_size = {width, height};
  report.jacobian.grid = {nx, ny};
  report.method = to_string(method);
  report.backend = backend->name();
  clock.finish(args.timings);
  print(report);
  return kExitOk;
}

}  // namespace

void add_check_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* cmd = root.add_subcommand(
      "check",
      "Validate a feature file and report trajectories, residuals, Jacobian statistics and distortion as JSON");
  cmd->add_option("--features", args->features, "feature file (JSON)")->required();
  cmd->add_option("--width", args->width, "output width (default: enough to hold every feature)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--height", args->height, "output height (default: enough to hold every feature)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--grid-step", args->grid_step,
                  "spacing of the Jacobian grid in pixels (default: at most 128 nodes per side)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--mirror", args->mirror,
                "check the warp of the texture flipped horizontally first (as the feature file's \"mirror\": true), "
                "about --width or the features' extent");
  cmd->add_option("--method", args->method, "field (default) or a baseline to compare: tps or mls")
      ->check(CLI::IsMember({"field", "tps", "mls"}));
  cmd->add_flag("--trajectories", args->trajectories,
                "also print the planned trajectories' waypoints (trajectory.waypoints, pre-aligned frame)");
  add_progress_option(*cmd, args->progress);
  add_timings_option(*cmd, args->timings);
  add_backend_options(*cmd, args->backend);
  cmd->callback([args, &action] { action = [args] { return run_check(*args); }; });
}

}  // namespace texwarp::cli
