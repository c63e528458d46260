// `texwarp map`: maps points through the warp (forward f, or inverse f⁻¹ with --inverse); JSON in and out.
#include <chrono>
#include <iostream>

#include "backend_choice.hpp"
#include "cli_command.hpp"
#include "command_clock.hpp"
#include "feature_file.hpp"
#include "interrupt_cancel.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"

namespace texwarp::cli {
namespace {

struct MapArgs {
  std::string features;
  std::string points;
  bool inverse = false;
  bool progress = false;
  std::string timings;  // "", "table" or "json"
  BackendChoice backend;
};

int run_map(const MapArgs& args) {
  const InterruptCancel interrupts;  // SIGINT and SIGTERM cancel the work below: exit 3, nothing written
  using proto::LatencyStage;
  CommandClock clock({LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup, LatencyStage::kPathlines,
                      LatencyStage::kWrite},
                     args.progress);
  std::vector<Point> points;
  const WarpProblem problem = clock.time(LatencyStage::kPlan, [&] {
    WarpProblem loaded = load_problem(args.features);
    const auto input = read_points_file(args.points);
    points.reserve(input.size());
    for (const auto& p : input) points.emplace_back(p[0], p[1]);
    // Each point's pathline, as an --exact warp's pixel's.
    runner::StageWorkload workload;
    workload.input_pixels = 0.0;
    workload.output_pixels = static_cast<double>(points.size());
    workload.features = loaded.size();
    workload.exact = true;
    clock.set_workload(workload);
    return loaded;
  });
  auto backend = clock.time(LatencyStage::kDeviceSetup, [&] { return make_backend(args.backend); });
  RunControl control;
  control.cancel = interrupts.flag();
  control.threads = args.backend.threads;
  control.progress = clock.progress_within(LatencyStage::kPathlines);
  clock.time(LatencyStage::kPathlines, [&] {
    map_points(*backend, problem, points, args.inverse ? Direction::kInverse : Direction::kForward, control);
  });
  const std::string text = clock.time(LatencyStage::kWrite, [&] {
    std::vector<std::array<double, 2>> out;
    out.reserve(points.size());
    for (const Point& p : points) out.push_back({p.real(), p.imag()});
    return proto::encode_points(out).dump();
  });
  clock.finish(args.timings);
  std::cout << text << "\n";
  return kExitOk;
}

}  // namespace

void add_map_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<MapArgs>();
  CLI::App* cmd = root.add_subcommand("map", "Map points through the warp; prints [[x, y], ...] in the given order");
  cmd->add_option("--features", args->features, "feature file (JSON)")->required();
  cmd->add_option("--points", args->points, "points file: [[x, y], ...] in pixels")->required();
  cmd->add_flag("--inverse", args->inverse, "apply the inverse map f⁻¹ (output pixels → source pixels)");
  add_progress_option(*cmd, args->progress);
  add_timings_option(*cmd, args->timings);
  add_backend_options(*cmd, args->backend);
  cmd->callback([args, &action] { action = [args] { return run_map(*args); }; });
}

}  // namespace texwarp::cli
