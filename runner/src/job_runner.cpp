// Running and pre-checking jobs: see job_runner.hpp.
#include "texwarp/runner/job_runner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

#include "texwarp/core/constraint_residuals.hpp"
#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/core/warp_certificate_json.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"
#include "texwarp/mesh/mapping_report.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/mesh/obj_output.hpp"
#include "texwarp/mesh/region_spec.hpp"
#include "texwarp/mesh/surface_feature_conversion.hpp"
#include "texwarp/mesh/texture_mapping.hpp"
#include "texwarp/mesh/uv_convention.hpp"

namespace texwarp::runner {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr int kJacobianMaxGridSide = 64;  // jacobian_check: at most this many grid nodes per side

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Runs f, whose input is the part of the job at `base`; an InputError from it is re-placed in the job document
// (InputLocation::rebased: a file it names, the server's own layout, is dropped).
template <typename F>
auto at_path(const JsonPath& base, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    throw InputError(e.where().rebased(base), e.detail());
  }
}

// A RunControl whose progress fractions land in [lo, hi] of the caller's.
RunControl phase(const RunControl& control, double lo, double hi) {
  RunControl c = control;
  if (control.progress) {
    c.progress = [progress = control.progress, lo, hi](double f) { progress(lo + (hi - lo) * std::clamp(f, 0.0, 1.0)); };
  }
  return c;
}

void report_progress(const RunControl& control, double fraction) {
  if (control.canceled()) throw CanceledError();
  if (control.progress) control.progress(fraction);
}

ImageHeader image_header(const proto::JobSpec& spec, InputResolver& inputs, const JobLimits& limits, std::string* file) {
  *file = inputs.image_file(spec.image, JsonPath{"image"});
  return at_path(JsonPath{"image"}, [&] { return read_image_header(*file, limits.image); });
}

void check_output_size(const proto::OutputSpec& output, const ImageHeader& header, const JobLimits& limits) {
  const long long w = output.width > 0 ? output.width : header.width;
  const long long h = output.height > 0 ? output.height : header.height;
  if (w * h > limits.max_output_pixels) {
    throw InputError(JsonPath{"output"}, "the warped image would have " + std::to_string(w) + "×" + std::to_string(h) +
                                     " pixels, more than this server's limit of " +
                                     std::to_string(limits.max_output_pixels));
  }
}

void check_feature_count(std::size_t count, const JobLimits& limits, const JsonPath& where) {
  if (count > limits.max_features) {
    throw InputError(where, std::to_string(count) + " features, more than the limit of " +
                                std::to_string(limits.max_features));
  }
}

WarpProblem image_problem(const proto::WarpSpec& warp) {
  return at_path(JsonPath{"warp"}, [&] { return WarpProblem(features_from_spec(warp), options_from_spec(warp)); });
}

PixelFormat output_format(const proto::OutputSpec& output, const ImageHeader& header) {
  return output.pixel_format.value_or(header.format);
}

constexpr const char* kMemoryFlag = "--max-job-memory-mb";

// The image warp's share of a job's memory (memory_estimate.hpp), from the texture's header and the output spec.
ImageWarpMemoryInput warp_memory(const proto::JobSpec& spec, const ImageHeader& header) {
  ImageWarpMemoryInput in;
  in.source = header;
  in.output_width = spec.output.width;
  in.output_height = spec.output.height;
  in.output_format = output_format(spec.output, header);
  in.transparent_border = spec.output.border == Border::kTransparent;
  in.positions = spec.options.exact ? PositionMethod::kPerPixel : PositionMethod::kLattice;
  return in;
}

// Refuses an image job whose buffers (source and output pixels, positions, lattice, encoder) would exceed the
// budget: checked on submission and again before any pixel is decoded.
void check_image_job_memory(const proto::JobSpec& spec, const ImageHeader& header, const JobLimits& limits) {
  check_memory_budget(image_warp_memory(warp_memory(spec, header)), limits.max_job_memory_bytes, JsonPath{"image"},
                      kMemoryFlag);
}

double degrees(double radians) { return radians * 180.0 / std::numbers::pi; }

nlohmann::json finish(const fs::path& out_dir, std::vector<JobFile>& files, nlohmann::json report,
                      const std::vector<std::pair<std::string, double>>& timings, Clock::time_point start) {
  nlohmann::json t = nlohmann::json::object();
  for (const auto& [name, s] : timings) t[name] = s;
  t["total_s"] = seconds_since(start);
  report["timings"] = std::move(t);
  nlohmann::json names = nlohmann::json::array();
  for (const auto& f : files) names.push_back(f.name);
  names.push_back(kReportFile);
  report["files"] = std::move(names);
  write_text_file_atomically((out_dir / kReportFile).string(), report.dump(2) + "\n");
  files.push_back({kReportFile, media_type_for(kReportFile)});
  return report;
}

JobOutput run_image_job(const proto::JobSpec& spec, InputResolver& inputs, BackendCache& backends, const fs::path& out_dir,
                        const JobLimits& limits, const RunControl& control) {
  const auto start = Clock::now();
  std::vector<std::pair<std::string, double>> timings;
  std::string file;
  const ImageHeader header = image_header(spec, inputs, limits, &file);
  check_output_size(spec.output, header, limits);
  check_feature_count(spec.warp->features.size(), limits, JsonPath{"warp", "features"});
  check_image_job_memory(spec, header, limits);
  auto t = Clock::now();
  const WarpProblem problem = image_problem(*spec.warp);
  WarpBackend& backend = backends.get(spec.options.device);
  timings.emplace_back("prepare_s", seconds_since(t));
  report_progress(control, 0.01);

  t = Clock::now();
  const Image source = at_path(JsonPath{"image"}, [&] { return read_image(file, limits.image); });
  timings.emplace_back("read_s", seconds_since(t));
  report_progress(control, 0.03);

  ImageWarpOptions options;
  options.width = spec.output.width;
  options.height = spec.output.height;
  options.interpolation = spec.output.interpolation;
  options.border = spec.output.border;
  options.exact = spec.options.exact;
  options.tolerance_px = spec.options.tolerance_px;
  t = Clock::now();
  WarpCertificate certificate;
  const Image warped = warp_image(backend, problem, source, options, phase(control, 0.03, 0.9), &certificate);
  timings.emplace_back("warp_s", seconds_since(t));

  t = Clock::now();
  const ConstraintResiduals residuals = constraint_residuals(backend, problem, phase(control, 0.9, 0.92));
  nlohmann::json per_feature = nlohmann::json::array();
  for (std::size_t i = 0; i < residuals.per_feature.size(); ++i) {
    per_feature.push_back({{"feature", describe_feature(problem.features(), i)},
                           {"id", problem.features()[i].id},
                           {"residual_px", residuals.per_feature[i]}});
  }
  timings.emplace_back("residuals_s", seconds_since(t));

  nlohmann::json jacobian = nullptr;
  if (spec.options.jacobian_check) {
    t = Clock::now();
    const int step = std::max(1, (std::max(warped.width, warped.height) + kJacobianMaxGridSide - 1) / kJacobianMaxGridSide);
    std::vector<Point> grid;
    for (int y = 0; y < warped.height; y += step) {
      for (int x = 0; x < warped.width; x += step) grid.emplace_back(x + 0.5, y + 0.5);
    }
    const JacobianStats stats = summarize_determinants(
        warp_jacobian_determinants(backend, problem, grid, Direction::kInverse, phase(control, 0.92, 0.97)));
    jacobian = {{"map", "inverse (output pixel → source pixel), variational equation at pixel centres"},
                {"step_px", step},
                {"samples", stats.samples},
                {"min_det", stats.min_det},
                {"max_det", stats.max_det},
                {"nonpositive", stats.nonpositive}};
    timings.emplace_back("jacobian_s", seconds_since(t));
  }
  report_progress(control, 0.97);

  t = Clock::now();
  const PixelFormat format = output_format(spec.output, header);
  const std::string image_name = warped_image_file(spec.output);
  write_image((out_dir / image_name).string(), warped, format);
  std::vector<JobFile> files = {{image_name, media_type_for(image_name)}};
  timings.emplace_back("write_s", seconds_since(t));

  std::size_t gradients = 0;
  for (const Feature& f : problem.features()) gradients += f.is_gradient() ? 1 : 0;
  const Similarity& s = problem.prealignment();
  nlohmann::json report;
  report["kind"] = "image";
  report["backend"] = backend.name();
  report["method"] = certificate.exact ? "per_pixel" : "certified_lattice";
  report["exact"] = certificate.exact;
  report["certificate"] = to_json(certificate);
  report["input"] = {{"width", header.width}, {"height", header.height}, {"channels", header.channels},
                     {"pixel_format", to_string(header.format)}};
  report["output"] = {{"file", image_name},
                      {"width", warped.width},
                      {"height", warped.height},
                      {"channels", warped.channels},
                      {"pixel_format", to_string(format)},
                      {"interpolation", to_string(spec.output.interpolation)},
                      {"border", to_string(spec.output.border)}};
  report["warp"] = {{"alpha", problem.alpha()},
                    {"prealign", problem.options().prealign == Prealign::kSimilarity ? "similarity" : "none"},
                    {"tolerance_px", problem.tolerance_px()},
                    {"features", problem.size()},
                    {"gradient_features", gradients}};
  report["prealignment"] = {{"scale", s.scale()}, {"angle_deg", degrees(s.angle_rad())},
                            {"translation", {s.b.real(), s.b.imag()}}};
  const ClosestApproach& ca = problem.closest_approach();
  report["closest_approach"] =
      std::isfinite(ca.distance_px)
          ? nlohmann::json{{"features", {describe_feature(problem.features(), ca.first),
                                         describe_feature(problem.features(), ca.second)}},
                           {"t", ca.t},
                           {"distance_px", ca.distance_px}}
          : nlohmann::json(nullptr);
  report["residuals"] = {{"max_px", residuals.max}, {"per_feature", std::move(per_feature)}};
  report["jacobian"] = std::move(jacobian);
  JobOutput out;
  out.report = finish(out_dir, files, std::move(report), timings, start);
  out.files = std::move(files);
  report_progress(control, 1.0);
  return out;
}

// A mesh job's memory besides the image warp, per mesh face (a vertex per two faces): alive throughout, the mesh,
// its topology, the region and the mapping's arrays, the OBJ and UV texts (~256 bytes); while flattening, the LSCM
// system (12 triplets and 12 non-zeros per face), its normal matrix and their LDLᵀ factor with its fill (~1.3 kB).
constexpr std::uint64_t kMeshResidentBytesPerFace = 256;
constexpr std::uint64_t kMeshSolveBytesPerFace = 1280;
// Before a mesh file is parsed its faces are estimated from its size: a face line plus its share of vertex lines.
constexpr std::uint64_t kMeshFileBytesPerFace = 24;

struct MeshSize {
  std::uint64_t faces = 0;       // exact once parsed, else estimated
  std::uint64_t text_bytes = 0;  // a mesh file or OBJ text, held whole while it is parsed
  bool estimated = false;
};

MeshSize mesh_size(const proto::MeshSourceSpec& source, InputResolver& inputs) {
  using Kind = proto::MeshSourceSpec::Kind;
  MeshSize size;
  if (source.kind == Kind::kInline) {
    size.faces = source.mesh.triangles.size();
    return size;
  }
  if (source.kind == Kind::kObjText) {
    const std::string& text = source.obj_text;
    size.text_bytes = text.size();
    for (std::size_t at = 0; at < text.size();) {
      if (text.compare(at, 2, "f ") == 0 || text.compare(at, 2, "f\t") == 0) ++size.faces;
      const auto next = text.find('\n', at);
      if (next == std::string::npos) break;
      at = next + 1;
    }
    return size;
  }
  std::error_code ec;
  const auto bytes = fs::file_size(inputs.mesh_file(source, JsonPath{"mesh", "source"}), ec);
  if (!ec) {
    size.text_bytes = bytes;
    size.faces = bytes / kMeshFileBytesPerFace;
    size.estimated = true;
  }
  return size;
}

MemoryPhase mesh_resident(const MeshSize& size) {
  return {{"mesh of " + std::string(size.estimated ? "about " : "") + std::to_string(size.faces) +
               " faces (topology, region, UVs)",
           size.faces * kMeshResidentBytesPerFace}};
}

// Refuses a mesh job whose mesh (flattening) or warped texture would exceed the budget; the error names the mesh
// when the mesh alone does not fit, else the image.
void check_mesh_job_memory(const proto::JobSpec& spec, const ImageHeader& header, const MeshSize& size,
                           const JobLimits& limits) {
  MemoryPhase flattening = mesh_resident(size);
  flattening.push_back({"LSCM system and factor", size.faces * kMeshSolveBytesPerFace});
  flattening.push_back({"mesh text", size.text_bytes});
  MemoryEstimate estimate;
  estimate.add_phase(flattening);
  check_memory_budget(estimate, limits.max_job_memory_bytes, JsonPath{"mesh", "source"}, kMemoryFlag);
  if (!spec.output.image) return;
  ImageWarpMemoryInput warp = warp_memory(spec, header);
  warp.resident = mesh_resident(size);
  estimate = image_warp_memory(warp);
  estimate.add_phase(flattening);
  check_memory_budget(estimate, limits.max_job_memory_bytes, JsonPath{"image"}, kMemoryFlag);
}

mesh::TriangleMesh load_mesh(const proto::MeshSourceSpec& source, InputResolver& inputs, const JobLimits& limits) {
  using Kind = proto::MeshSourceSpec::Kind;
  const JsonPath base{"mesh", "source"};
  mesh::TriangleMesh m;
  if (source.kind == Kind::kInline) {
    const JsonPath where = base.key("inline");
    m = mesh::mesh_from_spec(source.mesh);
    at_path(where, [&] { mesh::validate_mesh(m, mesh::MeshSource{{}, where}); });
    return m;
  }
  std::string text;
  JsonPath where = base;
  if (source.kind == Kind::kObjText) {
    text = source.obj_text;
    where = base.key("obj");
  } else {
    const std::string file = inputs.mesh_file(source, base);
    text = at_path(base, [&] { return read_text_file(file, limits.max_mesh_bytes); });
  }
  if (source.kind != Kind::kObjText && source.format == proto::MeshFormat::kJson) {
    const nlohmann::json j = at_path(where, [&] { return proto::parse_json(text, where.str()); });
    m = at_path(where, [&] { return mesh::mesh_from_spec(proto::decode_mesh_data(j)); });
    at_path(where, [&] { mesh::validate_mesh(m, mesh::MeshSource{{}, where}); });
  } else {
    m = at_path(where, [&] { return mesh::parse_obj_mesh(text, {}); });
    at_path(where, [&] { mesh::validate_mesh(m, mesh::MeshSource{}); });
  }
  return m;
}

mesh::SurfaceFeatureSet surface_features(const proto::MeshJobSpec& m, const JobLimits& limits) {
  check_feature_count(m.features.features.size(), limits, JsonPath{"mesh", "features", "features"});
  return mesh::surface_features_from_spec(m.features);
}

JobOutput run_mesh_job(const proto::JobSpec& spec, InputResolver& inputs, BackendCache& backends, const fs::path& out_dir,
                       const JobLimits& limits, const RunControl& control) {
  const auto start = Clock::now();
  std::vector<std::pair<std::string, double>> timings;
  const proto::MeshJobSpec& m = *spec.mesh;
  std::string file;
  const ImageHeader header = image_header(spec, inputs, limits, &file);
  check_output_size(spec.output, header, limits);
  const mesh::SurfaceFeatureSet features = surface_features(m, limits);
  const std::optional<mesh::RegionSpec>& region = m.region;
  const mesh::UvOrigin origin = spec.output.uv_origin;
  WarpBackend& backend = backends.get(spec.options.device);

  check_mesh_job_memory(spec, header, mesh_size(m.source, inputs), limits);

  auto t = Clock::now();
  const mesh::TriangleMesh triangle_mesh = load_mesh(m.source, inputs, limits);
  check_mesh_job_memory(spec, header, MeshSize{static_cast<std::uint64_t>(triangle_mesh.face_count()), 0, false},
                        limits);
  mesh::MeshRegion selected = at_path(region ? JsonPath{"mesh", "region"} : JsonPath{"mesh", "source"},
                                      [&] { return mesh::select_region(triangle_mesh, region, {}); });
  timings.emplace_back("mesh_s", seconds_since(t));
  report_progress(control, 0.05);

  mesh::TextureMappingOptions options;
  options.texture_width = header.width;
  options.texture_height = header.height;
  options.frame_width = spec.output.width;
  options.frame_height = spec.output.height;
  options.margin_px = m.margin_px;
  t = Clock::now();
  const mesh::TextureMapping mapping = at_path(JsonPath{"mesh", "features"}, [&] {
    return mesh::map_texture(backend, triangle_mesh, std::move(selected), features, options, phase(control, 0.05, 0.3));
  });
  const mesh::MappingQuality quality =
      mesh::evaluate_mapping(triangle_mesh, mapping, mapping.texture_px, options, m.per_triangle);
  timings.emplace_back("mapping_s", seconds_since(t));
  report_progress(control, 0.32);

  std::vector<JobFile> files;
  WarpCertificate certificate;
  std::vector<std::array<double, 2>> uvs;
  std::vector<std::array<double, 2>> warped_uvs;
  nlohmann::json vertex_ids = nlohmann::json::array();
  for (int i = 0; i < mapping.region.vertex_count(); ++i) {
    uvs.push_back(mesh::pixel_to_uv(mapping.texture_px[i], header.width, header.height, origin));
    warped_uvs.push_back(mesh::pixel_to_uv(mapping.frame.pixels[i], mapping.frame_width, mapping.frame_height, origin));
    vertex_ids.push_back(mapping.region.vertices[i]);
  }
  const std::string image_name = warped_image_file(spec.output);
  const std::string comment =
      "texwarp mesh job: " + std::to_string(mapping.region.face_count()) + " region faces textured, " +
      std::to_string(mapping.features.size()) + " features\nuv_origin " + to_string(origin) + "; UVs into " +
      (m.obj_uv == proto::ObjUv::kWarped ? "the warped texture " + image_name : std::string("the original texture")) +
      "\nvt per region vertex; faces outside the region have no vt";
  write_text_file_atomically((out_dir / kObjFile).string(), mesh::textured_obj_text(triangle_mesh, mapping.region,
                                                                    m.obj_uv == proto::ObjUv::kWarped ? warped_uvs : uvs, comment));
  files.push_back({kObjFile, media_type_for(kObjFile)});
  const nlohmann::json uv_doc = {{"uv_origin", to_string(origin)},
                                 {"texture", {{"width", header.width}, {"height", header.height}}},
                                 {"warped_texture", {{"width", mapping.frame_width}, {"height", mapping.frame_height}}},
                                 {"vertices", std::move(vertex_ids)},
                                 {"uv", uvs},
                                 {"warped_uv", warped_uvs}};
  write_text_file_atomically((out_dir / kUvFile).string(), uv_doc.dump() + "\n");
  files.push_back({kUvFile, media_type_for(kUvFile)});

  if (spec.output.image) {
    t = Clock::now();
    const Image source = at_path(JsonPath{"image"}, [&] { return read_image(file, limits.image); });
    ImageWarpOptions warp;
    warp.width = mapping.frame_width;
    warp.height = mapping.frame_height;
    warp.interpolation = spec.output.interpolation;
    warp.border = spec.output.border;
    warp.exact = spec.options.exact;
    warp.tolerance_px = spec.options.tolerance_px;
    const Image warped = warp_image(backend, *mapping.problem, source, warp, phase(control, 0.32, 0.97), &certificate);
    write_image((out_dir / image_name).string(), warped, output_format(spec.output, header));
    files.push_back({image_name, media_type_for(image_name)});
    timings.emplace_back("warp_s", seconds_since(t));
  }
  report_progress(control, 0.98);

  mesh::MappingReportOptions report_options;
  report_options.uv_origin = origin;
  report_options.per_triangle = m.per_triangle;
  report_options.per_vertex = m.per_vertex;
  nlohmann::json report = mesh::mapping_report(triangle_mesh, mapping, quality, options, report_options);
  report["kind"] = "mesh";
  report["backend"] = backend.name();
  report["method"] = !spec.output.image ? "none" : certificate.exact ? "per_pixel" : "certified_lattice";
  report["exact"] = spec.options.exact;
  report["certificate"] = spec.output.image ? to_json(certificate) : nlohmann::json(nullptr);
  JobOutput out;
  out.report = finish(out_dir, files, std::move(report), timings, start);
  out.files = std::move(files);
  report_progress(control, 1.0);
  return out;
}

}  // namespace

std::uint64_t default_job_memory_bytes(int concurrent_jobs) { return default_memory_budget(concurrent_jobs); }

std::string warped_image_file(const proto::OutputSpec& output) {
  return std::string("warped.") + to_string(output.file_format);
}

std::string media_type_for(const std::string& file_name) {
  const auto dot = file_name.rfind('.');
  const std::string ext = dot == std::string::npos ? "" : file_name.substr(dot + 1);
  if (ext == "png") return "image/png";
  if (ext == "tiff" || ext == "tif") return "image/tiff";
  if (ext == "exr") return "image/x-exr";
  if (ext == "obj") return "model/obj";
  if (ext == "json") return "application/json";
  return "application/octet-stream";
}

void validate_job(const proto::JobSpec& spec, InputResolver& inputs, const JobLimits& limits) {
  std::string file;
  const ImageHeader header = image_header(spec, inputs, limits, &file);
  check_output_size(spec.output, header, limits);
  if (spec.kind() == proto::JobKind::kImage) {
    if (!spec.output.image) {
      throw InputError(JsonPath{"output", "image"}, "an image job always writes the warped image; \"image\": false is for mesh jobs");
    }
    check_feature_count(spec.warp->features.size(), limits, JsonPath{"warp", "features"});
    check_image_job_memory(spec, header, limits);
    image_problem(*spec.warp);
    return;
  }
  surface_features(*spec.mesh, limits);
  check_mesh_job_memory(spec, header, mesh_size(spec.mesh->source, inputs), limits);
}

JobOutput run_job(const proto::JobSpec& spec, InputResolver& inputs, BackendCache& backends, const fs::path& out_dir,
                  const JobLimits& limits, const RunControl& control) {
  if (spec.kind() == proto::JobKind::kImage) return run_image_job(spec, inputs, backends, out_dir, limits, control);
  return run_mesh_job(spec, inputs, backends, out_dir, limits, control);
}

}  // namespace texwarp::runner
