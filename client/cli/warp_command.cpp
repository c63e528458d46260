// `texwarp warp`: warps an image file so that its features land on their targets.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <optional>

#include "backend_choice.hpp"
#include "cli_command.hpp"
#include "command_clock.hpp"
#include "feature_file.hpp"
#include "texture_flags.hpp"
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
#include "texwarp/core/sampling_report.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/core/warp_certificate_json.hpp"
#include "texwarp/core/warp_problem_report.hpp"
#include "texwarp/proto/job_report_codec.hpp"

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
  bool exact = false;
  double tolerance_px = 0.05;
  std::string certificate;
  std::string method = "field";
  bool progress = false;
  bool mirror = false;
  std::uint64_t max_job_memory_mb = 0;  // 0: half the machine's memory
  int png_level = proto::kDefaultPngCompressionLevel;
  std::string compression = "fast";
  std::string timings;  // "", "table" or "json"
  BackendChoice backend;
  TextureFlags texture;
};

// A baseline's warp (the side-by-side of the paper's Fig. 2): its inverse map at every pixel, and in the
// certificate its Jacobian determinant at every pixel (central differences of the closed-form map).
Image baseline_warp_image(WarpMethod method, const WarpProblem& problem, Image source, const ImageWarpOptions& options,
                          WarpCertificate& certificate, ResampleStats& sampled) {
  const int width = options.width > 0 ? options.width : source.width;
  const int height = options.height > 0 ? options.height : source.height;
  const std::vector<Point> positions = baseline_inverse_map_grid(method, problem, width, height);
  std::vector<Point> centres;
  centres.reserve(positions.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) centres.emplace_back(x + 0.5, y + 0.5);
  }
  const auto map = baseline_map(method, problem, true);
  const JacobianStats stats = summarize_determinants(jacobian_determinants(
      [&map](std::vector<Point>& p) {
        for (Point& q : p) q = map(q);
      },
      centres, kJacobianStepPx));
  certificate = WarpCertificate{};
  certificate.exact = true;
  certificate.min_jacobian_det = stats.min_det;
  certificate.nonpositive_jacobians = stats.nonpositive;
  certificate.sampled_pixels = stats.samples;
  return resample_image(std::move(source), positions, width, height,
                        SamplingOptions{options.interpolation, options.border, options.filter}, options.encoding, {},
                        &sampled);
}

double baseline_residual(WarpMethod method, const WarpProblem& problem) {
  const auto map = baseline_map(method, problem, false);
  double worst = 0.0;
  for (const Feature& f : problem.features()) worst = std::max(worst, std::abs(map(f.source) - f.target));
  return worst;
}

int run_warp(const WarpArgs& args) {
  using proto::LatencyStage;
  CommandClock clock({LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup, LatencyStage::kDecode,
                      LatencyStage::kPathlines, LatencyStage::kSampling, LatencyStage::kVerify, LatencyStage::kEncode,
                      LatencyStage::kWrite},
                     args.progress);
  const auto start = std::chrono::steady_clock::now();
  const WarpMethod method = parse_warp_method(args.method, InputLocation::flag("--method"));
  ImageWarpOptions options;
  const RoleAndPath input = split_role(args.input, "--in");
  PixelFormat format = PixelFormat::kUint8;
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
    // What the warp will allocate, from the header, before any pixel is decoded.
    const ImageHeader header = read_image_header(input.path);
    options.encoding = texture_encoding(header, input, args.texture, "--in");
    // A mirrored warp flips the texture first: its feature sources flip about the image's width.
    WarpProblem planned =
        mirror ? problem_from_spec(spec, args.features, header.width) : problem_from_spec(spec, args.features);
    format = args.format.empty() ? header.format
                                 : proto::parse_enum<PixelFormat>(args.format, InputLocation::flag("--format"));
    ImageWarpMemoryInput memory;
    memory.source = header;
    memory.output_width = args.width;
    memory.output_height = args.height;
    memory.output_format = format;
    memory.transparent_border = options.border == Border::kTransparent;
    memory.pyramid = options.filter == SamplingFilter::kFootprint;
    memory.positions = method != WarpMethod::kField ? PositionMethod::kBaseline
                       : args.exact                 ? PositionMethod::kPerPixel
                                                    : PositionMethod::kLattice;
    const std::string size = args.width > 0 || args.height > 0
                                 ? " (warped to " + std::to_string(args.width > 0 ? args.width : header.width) + "×" +
                                       std::to_string(args.height > 0 ? args.height : header.height) + ")"
                                 : "";
    // The file as the message names it: with the size it is warped to.
    check_memory_budget(image_warp_memory(memory), memory_budget_from_mib(args.max_job_memory_mb, 1),
                        InputLocation::file(input.path + size), "--max-job-memory-mb");
    chosen_device(args.backend);  // the flags are checked whether a device is opened or not
    workload = runner::image_workload(header, args.width, args.height, planned.size(), args.exact);
    return planned;
  });
  // A zero field's warp is its closed form (S⁻¹) and a baseline has its own: no device is opened for them (the
  // CPU backend measures a closed form's residuals).
  const bool closed_form = method == WarpMethod::kField && has_closed_form(problem);
  workload.pathlines = method == WarpMethod::kField && !closed_form;
  clock.set_workload(workload);
  std::unique_ptr<WarpBackend> backend;
  if (method == WarpMethod::kField && !closed_form) {
    backend = clock.time(LatencyStage::kDeviceSetup, [&] { return make_backend(args.backend); });
  } else {
    backend = std::make_unique<CpuBackend>();
  }
  Image source = clock.time(LatencyStage::kDecode, [&] {
    Image decoded = read_image(input.path);
    if (mirror) mirror_image(decoded);
    return decoded;
  });

  RunControl control;
  control.threads = args.backend.threads;
  control.progress = clock.progress_within(LatencyStage::kPathlines);
  WarpCertificate certificate;
  ImageWarpTimes warp_times;
  const Image warped = [&] {
    if (method == WarpMethod::kField)
      return warp_image(*backend, problem, std::move(source), options, control, &certificate, &warp_times);
    const auto baseline_start = std::chrono::steady_clock::now();
    Image out = baseline_warp_image(method, problem, std::move(source), options, certificate, warp_times.sampling);
    warp_times.map_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - baseline_start).count();
    return out;
  }();
  clock.add(LatencyStage::kPathlines, warp_times.map_s);
  clock.add(LatencyStage::kSampling, warp_times.sampling_s);
  const double max_residual = clock.time(LatencyStage::kVerify, [&] {
    return method == WarpMethod::kField ? constraint_residuals(*backend, problem).max
                                        : baseline_residual(method, problem);
  });
  ImageEncoding encoding;
  encoding.png_compression_level = args.png_level;
  encoding.compression = proto::parse_enum<Compression>(args.compression, InputLocation::flag("--compression"));
  ImageWriteTimes write_times;
  const WrittenImage written = write_image(args.output, warped, format, encoding, &write_times);
  clock.add(LatencyStage::kEncode, write_times.encode_s);
  clock.add(LatencyStage::kWrite, write_times.write_s);
  if (!args.certificate.empty()) {
    clock.time(LatencyStage::kWrite, [&] {
      proto::CertificateReport report = certificate_report(certificate);
      if (method == WarpMethod::kField) report.trajectory = trajectory_report(problem);
      write_text_file_atomically(args.certificate, proto::encode_certificate_report(report).dump(2) + "\n");
    });
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  clock.finish(args.timings);
  std::fprintf(stderr,
               "texwarp: wrote %s (%d×%d, %d channels, %s) with %zu features on %s in %.2f s; "
               "max constraint residual %.3g px; %s: %zu pathlines, error bound %.3g px, min det J %.3g; "
               "sampled as %s\n",
               args.output.c_str(), warped.width, warped.height, written.channels, to_string(written.format),
               problem.size(), method == WarpMethod::kField ? backend->name().c_str() : to_string(method), seconds,
               max_residual,
               closed_form         ? "closed form"
               : certificate.exact ? "exact"
                                   : "certified lattice",
               certificate.pathlines, certificate.max_error_px_bound, certificate.min_jacobian_det,
               describe_sampling(sampling_report(options, warp_times.sampling)).c_str());
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
  cmd->add_option("--in", args->input,
                  "source image (PNG, or any format OpenImageIO reads), as PATH or ROLE=PATH: ROLE color (filtered "
                  "in linear light; the default for 8/16-bit files), data (values as they are; the default for float "
                  "files) or normal (tangent-space normals, turned with the texture)")
      ->required();
  cmd->add_option("--out", args->output, "output image; the format follows the extension")->required();
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
                  "TIFF and EXR output: fast (default: TIFF zip level 1, EXR piz), none or small (zip level 9)")
      ->check(CLI::IsMember(proto::enum_names<Compression>()));
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
