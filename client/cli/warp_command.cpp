// `texwarp warp`: warps an image file so that its features land on their targets.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <mutex>

#include "backend_choice.hpp"
#include "cli_command.hpp"
#include "feature_file.hpp"
#include "texwarp/core/constraint_residuals.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"

namespace texwarp::cli {
namespace {

struct WarpArgs {
  std::string features;
  std::string input;
  std::string output;
  int width = 0;
  int height = 0;
  std::string interpolation = "bilinear";
  std::string border = "transparent";
  std::string format;
  bool progress = false;
  BackendChoice backend;
};

int run_warp(const WarpArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  const WarpProblem problem = load_problem(args.features);
  ImageWarpOptions options;
  options.width = args.width;
  options.height = args.height;
  options.interpolation = parse_interpolation(args.interpolation);
  options.border = parse_border(args.border);
  ImageHeader header;
  const Image source = read_image(args.input, {}, &header);
  const PixelFormat format = args.format.empty() ? header.format : parse_pixel_format(args.format);
  auto backend = make_backend(args.backend);

  RunControl control;
  control.threads = args.backend.threads;
  int last_percent = -1;
  if (args.progress) {
    control.progress = [&last_percent](double fraction) {
      const int percent = static_cast<int>(fraction * 100.0);
      if (percent != last_percent) {
        last_percent = percent;
        std::fprintf(stderr, "progress %d%%\n", percent);
      }
    };
  }
  const Image warped = warp_image(*backend, problem, source, options, control);
  write_image(args.output, warped, format);
  const ConstraintResiduals residuals = constraint_residuals(*backend, problem);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::fprintf(stderr, "texwarp: wrote %s (%d×%d, %d channels, %s) with %zu features on %s in %.2f s; "
               "max constraint residual %.3g px\n",
               args.output.c_str(), warped.width, warped.height, warped.channels, to_string(format),
               problem.size(), backend->name().c_str(), seconds, residuals.max);
  return kExitOk;
}

}  // namespace

void add_warp_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<WarpArgs>();
  CLI::App* cmd = root.add_subcommand("warp", "Warp an image so that each feature's source lands on its target");
  cmd->add_option("--features", args->features, "feature file (JSON)")->required();
  cmd->add_option("--in", args->input, "source image (any format OpenImageIO reads)")->required();
  cmd->add_option("--out", args->output, "output image; the format follows the extension")->required();
  cmd->add_option("--width", args->width, "output width in pixels (default: the source's)")->check(CLI::PositiveNumber);
  cmd->add_option("--height", args->height, "output height in pixels (default: the source's)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--interp", args->interpolation, "bilinear (default) or bicubic")
      ->check(CLI::IsMember({"bilinear", "bicubic"}));
  cmd->add_option("--border", args->border,
                  "outside the source: transparent (default; adds alpha if missing), clamp or repeat")
      ->check(CLI::IsMember({"transparent", "clamp", "repeat"}));
  cmd->add_option("--format", args->format, "output pixel type: uint8|uint16|half|float (default: the source's)")
      ->check(CLI::IsMember({"uint8", "uint16", "half", "float"}));
  cmd->add_flag("--progress", args->progress, "print 'progress N%' lines on stderr");
  add_backend_options(*cmd, args->backend);
  cmd->callback([args, &action] { action = [args] { return run_warp(*args); }; });
}

}  // namespace texwarp::cli
