// Planning a job: see job_plan.hpp.
#include "job_plan.hpp"

#include <algorithm>
#include <chrono>
#include <map>

#include "input_place.hpp"
#include "job_steps.hpp"
#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/input_faces.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/mesh/region_spec.hpp"
#include "texwarp/mesh/surface_feature_conversion.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"
#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/runner/mesh_memory.hpp"

namespace texwarp::runner {
namespace {

namespace fs = std::filesystem;

constexpr const char* kMemoryFlag = "--max-job-memory-mb";

// A map's file, header and role; `source` is at `where` in the job.
PlannedMap plan_map(const proto::ImageSourceSpec& source, std::string name, const JsonPath& where,
                    const proto::OutputSpec& output, InputResolver& inputs, const JobLimits& limits) {
  PlannedMap map;
  map.name = std::move(name);
  map.where = where;
  ImageHeader own;  // what the file (or each tile) declares, for the role's defaults
  const bool udim_path = source.kind == proto::ImageSourceSpec::Kind::kPath && has_udim_token(source.path);
  if (udim_path || source.kind == proto::ImageSourceSpec::Kind::kTiles) {
    // A <UDIM> path: the tiles that exist, found through the resolver (a tile it refuses or cannot find is missing).
    // Tiles given one by one: those, each resolved (an unknown blob is refused at its place, not taken as missing).
    std::map<int, std::string> given;  // tiles one by one: each resolved first, an error at its own place
    for (std::size_t i = 0; i < source.tiles.size(); ++i) {
      const proto::UdimTileSource& t = source.tiles[i];
      proto::ImageSourceSpec tile;
      tile.kind = t.blob.empty() ? proto::ImageSourceSpec::Kind::kBase64 : proto::ImageSourceSpec::Kind::kBlob;
      tile.blob = t.blob;
      tile.data = t.data;
      given[t.number] = inputs.image_file(tile, where.key("tiles").index(i));
    }
    const auto lookup = [&](int number) -> std::optional<std::string> {
      if (!udim_path) {
        const auto it = given.find(number);
        return it == given.end() ? std::nullopt : std::optional(it->second);
      }
      proto::ImageSourceSpec tile = source;
      tile.path = udim_tile_path(source.path, number);
      try {
        return inputs.image_file(tile, where);
      } catch (const InputError&) {
        return std::nullopt;
      }
    };
    if (output.width > 0 || output.height > 0) {
      throw InputError(JsonPath{"output"}, "a UDIM texture is warped on its canvas and cut into the same tiles: no "
                                           "\"width\" or \"height\"");
    }
    map.udim = at_path(where, [&] {
      return udim_path ? find_udim_tiles(source.path, JsonPath{"path"}, limits.image, lookup)
                       : find_udim_tiles("tiles", JsonPath{"tiles"}, limits.image, lookup);
    });
    map.header = map.udim->header(output.border == Border::kTransparent);
    own = map.udim->tile;
    map.image_file = map.name + "." + kUdimToken + "." + warped_image_extension(output);
  } else {
    map.texture_file = inputs.image_file(source, where);
    map.header = at_path(where, [&] { return read_image_header(map.texture_file, limits.image); });
    own = map.header;
    map.image_file = map.name + "." + warped_image_extension(output);
  }
  map.encoding = resolve_texture_encoding(own, source.role, source.color_space, source.normal_convention,
                                          where.key("role"), where.key("color_space"));
  map.output_format = output.pixel_format.value_or(map.header.format);
  return map;
}

// A mesh job's warped texture is the region's frame, not the texture's canvas: it cannot be cut into UDIM tiles.
void refuse_mesh_udim(const proto::JobSpec& spec, const PlannedMap& map, const proto::ImageSourceSpec& source) {
  if (spec.mesh && map.udim) {
    const bool tiles = source.kind == proto::ImageSourceSpec::Kind::kTiles;
    throw InputError(map.where.key(tiles ? "tiles" : "path"),
                     std::string("a mesh job warps its texture onto the region's frame, one image: give one tile's "
                                 "file, not ") +
                         (tiles ? "tiles" : "a <UDIM> path") + " (UDIM textures are for image jobs)");
  }
}

// The maps of the job: its single image ("warped"), or its texture set, every map of the first's size.
std::vector<PlannedMap> plan_maps(const proto::JobSpec& spec, InputResolver& inputs, const JobLimits& limits) {
  if (!spec.is_set()) {
    PlannedMap single = plan_map(spec.image, "warped", JsonPath{"image"}, spec.output, inputs, limits);
    refuse_mesh_udim(spec, single, spec.image);
    if (!single.udim) single.image_file = warped_image_file(spec.output);
    return {std::move(single)};
  }
  std::vector<PlannedMap> maps;
  for (std::size_t i = 0; i < spec.images.size(); ++i) {
    const JsonPath where = JsonPath{"images"}.index(i);
    maps.push_back(plan_map(spec.images[i].source, spec.images[i].name, where, spec.output, inputs, limits));
    refuse_mesh_udim(spec, maps.back(), spec.images[i].source);
    const ImageHeader& h = maps.back().header;
    const ImageHeader& first = maps.front().header;
    if (h.width != first.width || h.height != first.height) {
      throw InputError(where, "is " + std::to_string(h.width) + "×" + std::to_string(h.height) + ", images[0] " +
                                  std::to_string(first.width) + "×" + std::to_string(first.height) +
                                  ": the maps of a set share one warp, and so their size");
    }
  }
  return maps;
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

// The warp's problem; with `mirror`, on the texture flipped horizontally (its width in pixels).
WarpProblem image_problem(const proto::WarpSpec& warp, int texture_width) {
  return at_path(JsonPath{"warp"}, [&] {
    std::vector<Feature> features = features_from_spec(warp);
    if (warp.mirror) features = mirror_features(std::move(features), texture_width);
    return WarpProblem(std::move(features), options_from_spec(warp));
  });
}

// The image warp's share of a job's memory (memory_estimate.hpp), from the texture's header and the output spec.
ImageWarpMemoryInput warp_memory(const proto::JobSpec& spec, const ImageHeader& header) {
  ImageWarpMemoryInput in;
  in.source = header;
  in.output_width = spec.output.width;
  in.output_height = spec.output.height;
  in.output_format = spec.output.pixel_format.value_or(header.format);
  in.transparent_border = spec.output.border == Border::kTransparent;
  in.pyramid = spec.output.filter == SamplingFilter::kFootprint;
  in.positions = spec.options.exact ? PositionMethod::kPerPixel : PositionMethod::kLattice;
  return in;
}

// Refuses an image job whose buffers (source and output pixels, positions, lattice, encoder) would exceed the
// budget, before any pixel is decoded. A set's maps are warped one after another, each map's write beside the next
// one's decode (texture_set_phases): each phase must fit.
void check_image_job_memory(const proto::JobSpec& spec, const std::vector<PlannedMap>& maps, const JobLimits& limits) {
  texture_set_phases(
      maps.size(), [&](std::size_t i) { return warp_memory(spec, maps[i].header); },
      [&](const MemoryEstimate& estimate, std::size_t i) {
        check_memory_budget(estimate, limits.max_job_memory_bytes, maps[i].where, kMemoryFlag);
      });
}

// Before a mesh file is parsed its faces are estimated from its size: a face line plus its share of vertex lines.
constexpr std::uint64_t kMeshFileBytesPerFace = 24;

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

// Refuses a mesh job whose mesh (flattening) or warped texture would exceed the budget; the error names the mesh
// when the mesh alone does not fit, else the image. Returns the estimated peak.
std::uint64_t check_mesh_job_memory(const proto::JobSpec& spec, const std::vector<PlannedMap>& maps,
                                    const MeshSize& size, const JobLimits& limits) {
  const MemoryPhase flattening = mesh_flattening(size);
  MemoryEstimate estimate;
  estimate.add_phase(flattening);
  check_memory_budget(estimate, limits.max_job_memory_bytes, JsonPath{"mesh", "source"}, kMemoryFlag);
  if (!spec.output.image) return estimate.peak_bytes();
  // A set's maps are sampled one after another, each map's write beside the next one's decode: each phase must fit
  // beside the mesh.
  std::uint64_t peak = estimate.peak_bytes();
  texture_set_phases(
      maps.size(),
      [&](std::size_t i) {
        ImageWarpMemoryInput warp = warp_memory(spec, maps[i].header);
        warp.resident = mesh_resident(size);
        return warp;
      },
      [&](const MemoryEstimate& phase, std::size_t i) {
        check_memory_budget(phase, limits.max_job_memory_bytes, maps[i].where, kMemoryFlag);
        peak = std::max(peak, phase.peak_bytes());
      });
  return peak;
}

mesh::MeshFile load_mesh(const proto::MeshSourceSpec& source, InputResolver& inputs, const JobLimits& limits) {
  using Kind = proto::MeshSourceSpec::Kind;
  const JsonPath base{"mesh", "source"};
  mesh::MeshFile m;
  if (source.kind == Kind::kInline) {
    const JsonPath where = base.key("inline");
    m.format = proto::MeshFormat::kJson;
    m.mesh = mesh::mesh_from_spec(source.mesh);
    m.faces = mesh::InputFaces::identity(m.mesh.face_count());
    at_path(where, [&] { mesh::validate_mesh(m.mesh, mesh::MeshSource{{}, where}); });
    return m;
  }
  std::string text;
  JsonPath where = base;
  proto::MeshFormat format = source.format;
  if (source.kind == Kind::kObjText) {
    text = source.obj_text;
    where = base.key("obj");
    format = proto::MeshFormat::kObj;
  } else {
    const std::string file = inputs.mesh_file(source, base);
    text = at_path(base, [&] { return read_text_file(file, limits.max_mesh_bytes); });
  }
  if (format == proto::MeshFormat::kJson) {
    const nlohmann::json j = at_path(where, [&] { return proto::parse_json(text, where.str()); });
    m.format = format;
    m.mesh = at_path(where, [&] { return mesh::mesh_from_spec(proto::decode_mesh_data(j)); });
    m.faces = mesh::InputFaces::identity(m.mesh.face_count());
    at_path(where, [&] { mesh::validate_mesh(m.mesh, mesh::MeshSource{{}, where}); });
    return m;
  }
  m = at_path(where, [&] {
    return mesh::parse_mesh_bytes(text, format, source.gltf.value_or(proto::GltfSelectionSpec{}), {});
  });
  at_path(where, [&] { mesh::validate_mesh(m.mesh, mesh::MeshSource{}); });
  return m;
}

mesh::SurfaceFeatureSet surface_features(const proto::MeshJobSpec& m, const JobLimits& limits) {
  check_feature_count(m.features.features.size(), limits, JsonPath{"mesh", "features", "features"});
  return mesh::surface_features_from_spec(m.features);
}

ImagePlan plan_image(const proto::JobSpec& spec, const std::vector<PlannedMap>& maps, const JobLimits& limits) {
  if (!spec.output.image) {
    throw InputError(JsonPath{"output", "image"},
                     "an image job always writes the warped image; \"image\": false is for mesh jobs");
  }
  check_feature_count(spec.warp->features.size(), limits, JsonPath{"warp", "features"});
  check_image_job_memory(spec, maps, limits);
  return ImagePlan{image_problem(*spec.warp, maps.front().header.width)};
}

MeshPlan plan_mesh(const proto::JobSpec& spec, const std::vector<PlannedMap>& maps, InputResolver& inputs,
                   const JobLimits& limits, PlanScope scope) {
  const ImageHeader& header = maps.front().header;
  const proto::MeshJobSpec& m = *spec.mesh;
  MeshPlan plan;
  plan.features = surface_features(m, limits);
  plan.region = m.region;
  plan.uv_origin = spec.output.uv_origin;
  plan.mapping.texture_width = header.width;
  plan.mapping.texture_height = header.height;
  plan.mapping.frame_width = spec.output.width;
  plan.mapping.frame_height = spec.output.height;
  plan.mapping.margin_px = m.margin_px;
  plan.mapping.optimize = spec.options.optimize;
  check_mesh_job_memory(spec, maps, mesh_size(m.source, inputs), limits);
  // Refinement by default; asked for on a glTF primitive that cannot take new vertices (compressed), refused.
  plan.mapping.refine = spec.options.refine.value_or(true);
  if (scope == PlanScope::kSubmission) return plan;

  const auto start = std::chrono::steady_clock::now();
  plan.file = load_mesh(m.source, inputs, limits);
  if (plan.file.gltf != nullptr && !plan.file.gltf->unrefinable.empty()) {
    if (spec.options.refine.value_or(false)) {
      throw InputError(JsonPath{"options", "refine"},
                       "this glTF primitive cannot take new vertices: " + plan.file.gltf->unrefinable);
    }
    plan.mapping.refine = false;
  }
  plan.mesh = std::move(plan.file.mesh);
  const std::uint64_t peak =
      check_mesh_job_memory(spec, maps,
                            MeshSize{static_cast<std::uint64_t>(plan.mesh->face_count()), 0, false,
                                     plan.file.gltf != nullptr ? plan.file.gltf->kept_bytes(plan.mapping.refine) : 0},
                            limits);
  // Region face ids and face targets name input faces (an OBJ's quads and n-gons): moved onto the triangles here.
  plan.features = at_path(JsonPath{"mesh", "features"},
                          [&] { return mesh::features_on_triangles(std::move(plan.features), plan.file.faces); });
  plan.selected = at_path(plan.region ? JsonPath{"mesh", "region"} : JsonPath{"mesh", "source"}, [&] {
    std::optional<mesh::RegionSpec> region;
    if (plan.region) region = mesh::region_on_triangles(*plan.region, plan.file.faces, {});
    return mesh::select_region(*plan.mesh, region, {});
  });
  plan.mapping.max_refined_vertices =
      refined_vertex_budget(limits.max_job_memory_bytes, peak, plan.selected->vertex_count());
  plan.load_seconds = seconds_since(start);
  return plan;
}

}  // namespace

JobPlan plan_job(const proto::JobSpec& spec, InputResolver& inputs, const JobLimits& limits, PlanScope scope) {
  const auto start = std::chrono::steady_clock::now();
  JobPlan plan;
  plan.spec = &spec;
  plan.maps = plan_maps(spec, inputs, limits);
  const PlannedMap& first = plan.maps.front();
  plan.texture_file = first.texture_file;
  plan.header = first.header;
  check_output_size(spec.output, plan.header, limits);
  plan.output_format = first.output_format;
  plan.image_file = first.image_file;
  plan.warp.width = spec.output.width;
  plan.warp.height = spec.output.height;
  plan.warp.interpolation = spec.output.interpolation;
  plan.warp.border = spec.output.border;
  plan.warp.filter = spec.output.filter;
  plan.warp.encoding = first.encoding;
  plan.warp.exact = spec.options.exact;
  plan.warp.tolerance_px = spec.options.tolerance_px;
  if (spec.kind() == proto::JobKind::kImage) {
    plan.image = plan_image(spec, plan.maps, limits);
  } else {
    plan.mesh = plan_mesh(spec, plan.maps, inputs, limits, scope);
  }
  plan.seconds = seconds_since(start);
  return plan;
}

}  // namespace texwarp::runner
