// `texwarp map`: maps points through the warp (forward f, or inverse f⁻¹ with --inverse); JSON in and out.
#include <iostream>

#include "backend_choice.hpp"
#include "cli_command.hpp"
#include "feature_file.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"

namespace texwarp::cli {
namespace {

struct MapArgs {
  std::string features;
  std::string points;
  bool inverse = false;
  BackendChoice backend;
};

int run_map(const MapArgs& args) {
  const WarpProblem problem = load_problem(args.features);
  const auto input = read_points_file(args.points);
  std::vector<Point> points;
  points.reserve(input.size());
  for (const auto& p : input) points.emplace_back(p[0], p[1]);
  auto backend = make_backend(args.backend);
  RunControl control;
  control.threads = args.backend.threads;
  map_points(*backend, problem, points, args.inverse ? Direction::kInverse : Direction::kForward, control);
  std::vector<std::array<double, 2>> out;
  out.reserve(points.size());
  for (const Point& p : points) out.push_back({p.real(), p.imag()});
  std::cout << proto::encode_points(out).dump() << "\n";
  return kExitOk;
}

}  // namespace

void add_map_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<MapArgs>();
  CLI::App* cmd = root.add_subcommand("map", "Map points through the warp; prints [[x, y], ...] in the given order");
  cmd->add_option("--features", args->features, "feature file (JSON)")->required();
  cmd->add_option("--points", args->points, "points file: [[x, y], ...] in pixels")->required();
  cmd->add_flag("--inverse", args->inverse, "apply the inverse map f⁻¹ (output pixels → source pixels)");
  add_backend_options(*cmd, args->backend);
  cmd->callback([args, &action] { action = [args] { return run_map(*args); }; });
}

}  // namespace texwarp::cli
