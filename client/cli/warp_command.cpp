// `texwarp warp`: warps an image file so that its features land on their targets.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <optional>

#include "backend_choice.hpp"
#include "cli_command.hpp"
#include "command_clock.hpp"
#include "feature_file.hpp"
#include "interrupt_cancel.hpp"
#include "output_paths.hpp"
#include "texture_flags.hpp"
#include "texture_set.hpp"
#include "texwarp/core/baseline_warp.hpp"
#include "texwarp/core/closed_form_warp.hpp"
#include "texwarp/core/constraint_residuals.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/core/warp_certificate_json.hpp"
#include "texwarp/core/warp_problem_report.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/job_spec.hpp"

namespace texwarp::cli {
namespace {

struct WarpArgs {
  std::string features;
  std::vector<std::string> inputs;  // [ROLE=]PATH, one or more (a texture set)
  std::string output;               // one input
  std::string out_dir;              // any number of inputs: each output keeps its input's file name
  int width = 0;
  int height = 0;
  std::string interpolation = "bilinear";
  std::string border = "transparent";
  std::string format;
  bool exact = false;
  double tolerance_px = 0.05;
  std::string certificate;
  std::string method = "field";
  bool progress = false;
  bool mirror = false;
  std::uint64_t max_job_memory_mb = 0;  // 0: half the machine's memory
  int png_level = proto::kDefaultPngCompressionLevel;
  std::string compression = "fast";
  std::string timings;          // "", "table" or "json"
  bool texture_output = false;  // TIFF and EXR outputs as render-ready textures (always for .tx)
  BackendChoice backend;
  TextureFlags texture;
};

// A baseline's inverse map of the output grid (the side-by-side of the paper's Fig. 2), and in its certificate its
// Jacobian determinant at every pixel (central differences of the closed-form map).
OutputGridMap baseline_output_grid(WarpMethod method, const WarpProblem& problem, int width, int height) {
  const auto start = std::chrono::steady_clock::now();
  OutputGridMap grid;
  grid.width = width;
  grid.height = height;
  grid.positions = baseline_inverse_map_grid(method, problem, width, height);
  std::vector<Point> centres;
  centres.reserve(grid.positions.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) centres.emplace_back(x + 0.5, y + 0.5);
  }
  const auto map = baseline_map(method, problem, true);
  const JacobianStats stats = summarize_determinants(jacobian_determinants(
      [&map](std::vector<Point>& p) {
        for (Point& q : p) q = map(q);
      },
      centres, kJacobianStepPx));
  grid.certificate.exact = true;
  grid.certificate.min_jacobian_det = stats.min_det;
  grid.certificate.nonpositive_jacobians = stats.nonpositive;
  grid.certificate.sampled_pixels = stats.samples;
  grid.map_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return grid;
}

double baseline_residual(WarpMethod method, const WarpProblem& problem) {
  const auto map = baseline_map(method, problem, false);
  double worst = 0.0;
  for (const Feature& f : problem.features()) worst = std::max(worst, std::abs(map(f.source) - f.target));
  return worst;
}

int run_warp(const WarpArgs& args) {
  const InterruptCancel interrupts;  // SIGINT and SIGTERM cancel the work below: exit 3, nothing written
  namespace fs = std::filesystem;
  using proto::LatencyStage;
  // The stages in the order they run: the output grid's map and its check, then each map of the set read, sampled,
  // encoded and written.
  CommandClock clock({LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup, LatencyStage::kPathlines,
                      LatencyStage::kVerify, LatencyStage::kDecode, LatencyStage::kSampling, LatencyStage::kEncode,
                      LatencyStage::kWrite},
                     args.progress);
  const auto start = std::chrono::steady_clock::now();
  const WarpMethod method = parse_warp_method(args.method, InputLocation::flag("--method"));
  ImageWarpOptions options;
  std::vector<SetMap> maps;
  proto::WarpSpec spec;
  bool mirror = false;
  runner::StageWorkload workload;
  const WarpProblem problem = clock.time(LatencyStage::kPlan, [&] {
    spec = read_feature_file(args.features);
    mirror = spec.mirror || args.mirror;
    options.width = args.width;
    options.height = args.height;
    options.interpolation = proto::parse_enum<Interpolation>(args.interpolation, InputLocation::flag("--interp"));
    options.border = proto::parse_enum<Border>(args.border, InputLocation::flag("--border"));
    options.filter = texture_filter(args.texture);
    options.exact = args.exact;
    options.tolerance_px = args.tolerance_px;
    std::optional<PixelFormat> asked;
    if (!args.format.empty()) asked = proto::parse_enum<PixelFormat>(args.format, InputLocation::flag("--format"));
    SetFlags flags;
    flags.resized = args.width > 0 ? "--width" : args.height > 0 ? "--height" : "";
    maps = plan_set_maps(args.inputs, args.output, args.out_dir, asked, args.texture, options.border, flags);
    if (args.texture_output) {
      for (const SetMap& map : maps) {
        const std::string ext = fs::path(map.output).extension().string();
        if (ext != ".tx" && ext != ".tif" && ext != ".tiff" && ext != ".exr") {
          throw InputError(InputLocation::flag("--texture"), map.output + ": a render-ready texture is a .tx, .tif, "
                                                                          ".tiff or .exr file");
        }
      }
    }
    const ImageHeader& first = maps.front().header;
    // A mirrored warp flips the texture first: its feature sources flip about the image's width.
    WarpProblem planned =
        mirror ? problem_from_spec(spec, args.features, first.width) : problem_from_spec(spec, args.features);
    // The maps are warped one after another, each but the first decoded while the one before it is written: the
    // peak is the largest map's warp, or of such an overlap.
    const auto memory_of = [&](const SetMap& map) {
      ImageWarpMemoryInput memory =
          set_map_memory(maps, map, args.width, args.height, options.border, options.filter);  // (PrefetchedSource)
      memory.positions = method != WarpMethod::kField ? PositionMethod::kBaseline
                         : args.exact                 ? PositionMethod::kPerPixel
                                                      : PositionMethod::kLattice;
      return memory;
    };
    const std::string size = args.width > 0 || args.height > 0
                                 ? " (warped to " + std::to_string(args.width > 0 ? args.width : first.width) + "×" +
                                       std::to_string(args.height > 0 ? args.height : first.height) + ")"
                                 : "";
    const std::uint64_t budget = memory_budget_from_mib(args.max_job_memory_mb, 1);
    check_set_memory(maps, memory_of, budget, size, "--max-job-memory-mb");
    chosen_device(args.backend);  // the flags are checked whether a device is opened or not
    workload = runner::image_workload(first, args.width, args.height, planned.size(), args.exact);
    workload.maps = maps.size();
    return planned;
  });
  // A zero field's warp is its closed form (S⁻¹) and a baseline has its own: no device is opened for them (the
  // CPU backend measures a closed form's residuals).
  const bool closed_form = method == WarpMethod::kField && has_closed_form(problem);
  workload.pathlines = method == WarpMethod::kField && !closed_form;
  clock.set_workload(workload);
  // Outputs that cannot be written fail now, not after the pathlines.
  check_set_outputs(maps, args.out_dir, SetFlags{});
  check_output_file("--certificate", args.certificate);
  // The first map is decoded while the device is set up and the output grid mapped.
  PrefetchedSource first_source(maps, options.border, mirror);
  std::unique_ptr<WarpBackend> backend;
  if (method == WarpMethod::kField && !closed_form) {
    backend = clock.time(LatencyStage::kDeviceSetup, [&] { return make_backend(args.backend); });
  } else {
    backend = std::make_unique<CpuBackend>();
  }

  // The map of the output grid, once for every map of the set.
  RunControl control;
  control.threads = args.backend.threads;
  control.cancel = interrupts.flag();
  control.progress = clock.progress_within(LatencyStage::kPathlines);
  const ImageHeader& first = maps.front().header;
  const bool positions_needed =
      std::any_of(maps.begin(), maps.end(), [](const SetMap& m) { return m.encoding.role == ImageRole::kNormal; });
  const OutputGridMap grid =
      method == WarpMethod::kField
          ? map_output_grid(*backend, problem, first.width, first.height, options, positions_needed, control)
          : baseline_output_grid(method, problem, args.width > 0 ? args.width : first.width,
                                 args.height > 0 ? args.height : first.height);
  clock.add(LatencyStage::kPathlines, grid.map_s);
  const WarpCertificate& certificate = grid.certificate;
  const double max_residual = clock.time(LatencyStage::kVerify, [&] {
    return method == WarpMethod::kField ? constraint_residuals(*backend, problem).max
                                        : baseline_residual(method, problem);
  });

  // Each map in turn: read, sampled with its role, written (staged: the set's files appear together, or none).
  SetWarp warp;
  warp.options = options;
  warp.encoding.png_compression_level = args.png_level;
  warp.encoding.compression = proto::parse_enum<Compression>(args.compression, InputLocation::flag("--compression"));
  warp.texture_output = args.texture_output;
  warp.mirror = mirror;
  warp.control.threads = args.backend.threads;
  warp.control.cancel = interrupts.flag();
  warp.folder = args.out_dir;
  std::vector<std::string> summaries;
  for (const WrittenSetMap& written : warp_set_maps(grid, maps, warp, clock, &first_source))
    summaries.push_back(written.summary);
  if (!args.certificate.empty()) {
    clock.time(LatencyStage::kWrite, [&] {
      proto::CertificateReport report = certificate_report(certificate);
      if (method == WarpMethod::kField) report.trajectory = trajectory_report(problem);
      write_text_file_atomically(args.certificate, proto::encode_certificate_report(report).dump(2) + "\n");
    });
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  clock.finish(args.timings);
  // One map: one line, "wrote … with … features …; sampled as …"; a set: a line per map, then the warp's.
  const std::string head = maps.size() == 1 ? summaries[0].substr(0, summaries[0].find("; sampled as "))
                                            : "warped " + std::to_string(maps.size()) + " maps";
  if (maps.size() > 1) {
    for (const std::string& s : summaries) std::fprintf(stderr, "texwarp: %s\n", s.c_str());
  }
  std::fprintf(stderr,
               "texwarp: %s with %zu features on %s in %.2f s; "
               "max constraint residual %.3g px; %s: %zu pathlines, error bound %.3g px, min det J %.3g%s\n",
               head.c_str(), problem.size(), method == WarpMethod::kField ? backend->name().c_str() : to_string(method),
               seconds, max_residual,
               closed_form         ? "closed form"
               : certificate.exact ? "exact"
                                   : "certified lattice",
               certificate.pathlines, certificate.max_error_px_bound, certificate.min_jacobian_det,
               maps.size() == 1 ? summaries[0].substr(summaries[0].find("; sampled as ")).c_str() : "");
  if (backend) say_double_retries(*backend, "warp");
  if (certificate.nonpositive_jacobians > 0) {
    std::fprintf(stderr, "texwarp: the map folds over at %zu sampled pixels (det J ≤ 0)\n",
                 certificate.nonpositive_jacobians);
  }
  const proto::MirrorReport found = mirror_report(features_from_spec(spec), mirror);
  if (found.suggestion) std::fprintf(stderr, "texwarp: %s\n", found.suggestion->c_str());
  if (mirror) std::fprintf(stderr, "texwarp: the texture was flipped horizontally first (mirror)\n");
  return kExitOk;
}

}  // namespace

void add_warp_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<WarpArgs>();
  CLI::App* cmd = root.add_subcommand("warp", "Warp an image so that each feature's source lands on its target");
  cmd->add_option("--features", args->features, "feature file (JSON)")->required();
  cmd->add_option("--in", args->inputs,
                  "source image (PNG, or any format OpenImageIO reads), as PATH or ROLE=PATH: ROLE color (filtered "
                  "in linear light; the default for 8/16-bit files), data (values as they are; the default for float "
                  "files) or normal (tangent-space normals, turned with the texture). Repeat it for the maps of a "
                  "texture set (same size): the map is computed once and each map sampled with its role")
      ->required();
  cmd->add_option("--out", args->output, "output image of a single --in; the format follows the extension");
  cmd->add_option("--out-dir", args->out_dir,
                  "output folder for any number of --in: each output keeps its input's file name (and format)");
  cmd->add_option("--width", args->width, "output width in pixels (default: the source's)")->check(CLI::PositiveNumber);
  cmd->add_option("--height", args->height, "output height in pixels (default: the source's)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--interp", args->interpolation, "bilinear (default) or bicubic")
      ->check(CLI::IsMember(proto::enum_names<Interpolation>()));
  cmd->add_option("--border", args->border,
                  "outside the source: transparent (default; adds alpha if missing), clamp or repeat")
      ->check(CLI::IsMember(proto::enum_names<Border>()));
  cmd->add_option("--format", args->format, "output pixel type: uint8|uint16|half|float (default: the source's)")
      ->check(CLI::IsMember(proto::enum_names<PixelFormat>()));
  cmd->add_option("--method", args->method,
                  "field (this method, default), or a baseline for comparison: tps (thin-plate spline) or mls "
                  "(moving least squares); baselines ignore frames and may fold")
      ->check(CLI::IsMember({"field", "tps", "mls"}));
  cmd->add_flag("--exact", args->exact, "a pathline for every output pixel (default: the certified lattice)");
  cmd->add_option("--tolerance-px", args->tolerance_px,
                  "bound on each pixel's source position error on the lattice path (default 0.05)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--certificate", args->certificate,
                  "write the warp's certificate (errors, min det J, pathlines) as JSON to this file");
  add_progress_option(*cmd, args->progress);
  add_timings_option(*cmd, args->timings);
  cmd->add_option("--png-level", args->png_level,
                  "zlib level of a PNG output: 0 (stored) to 9 (smallest); default 1, the fastest that compresses "
                  "(same pixels at every level)")
      ->check(CLI::Range(0, proto::kMaxPngCompressionLevel));
  cmd->add_option("--compression", args->compression,
                  "TIFF and EXR output: fast (default: zip level 1), none or small (zip level 9)")
      ->check(CLI::IsMember(proto::enum_names<Compression>()));
  cmd->add_flag("--texture", args->texture_output,
                "write TIFF and EXR outputs as render-ready textures (OpenImageIO's make_texture: tiled, MIP-mapped, "
                "the role's colour space recorded); a .tx output always is one");
  cmd->add_flag("--mirror", args->mirror,
                "flip the texture horizontally first (sources x → width − x), then warp: for targets laid out as a "
                "mirror image of the sources (as the feature file's \"mirror\": true)");
  cmd->add_option("--max-job-memory-mb", args->max_job_memory_mb,
                  "refuse a warp estimated to need more memory than this, MiB (default: half the machine's memory)");
  add_texture_options(*cmd, args->texture);
  add_backend_options(*cmd, args->backend);
  cmd->callback([args, &action] { action = [args] { return run_warp(*args); }; });
}

}  // namespace texwarp::cli
