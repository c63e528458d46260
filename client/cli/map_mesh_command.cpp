// `texwarp map-mesh`: mesh + texture + surface features (+ region) → OBJ or glTF with UVs, warped texture, report.
#include "map_mesh_command.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <system_error>
#include <vector>

#include "backend_choice.hpp"
#include "command_clock.hpp"
#include "feature_file.hpp"
#include "interrupt_cancel.hpp"
#include "output_paths.hpp"
#include "texture_flags.hpp"
#include "texture_set.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/sampling_report.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/gltf_output.hpp"
#include "texwarp/mesh/input_faces.hpp"
#include "texwarp/mesh/mapping_report.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/obj_output.hpp"
#include "texwarp/mesh/region_spec.hpp"
#include "texwarp/mesh/surface_feature_conversion.hpp"
#include "texwarp/mesh/texture_mapping.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"
#include "texwarp/runner/mesh_memory.hpp"

namespace texwarp::cli {
namespace {

struct MapMeshArgs {
  std::string mesh;
  std::vector<std::string> textures;  // [ROLE=]PATH, one or more (a texture set)
  std::string features;
  std::string region;
  std::string out_obj;
  std::string out_gltf;
  std::string gltf_mesh;  // a name, or an index when all digits
  int gltf_primitive = 0;
  std::string out_texture;  // one texture's warped output
  std::string out_dir;      // any number's: each keeps its input's file name
  std::string report;
  std::string uv_origin = "bottom_left";
  std::string obj_uv = "original";
  double margin_px = 8.0;
  int width = 0;
  int height = 0;
  std::string interpolation = "bilinear";
  std::string border = "transparent";
  std::string format;
  bool per_triangle = false;
  bool per_vertex = false;
  bool refine = false;     // --refine: asked for (a compressed glTF primitive then refused)
  bool no_refine = false;  // --no-refine: keep the input's faces (flips may remain)
  std::string optimize = "stretch";
  std::uint64_t max_job_memory_mb = 0;  // 0: half the machine's memory
  int png_level = proto::kDefaultPngCompressionLevel;
  std::string compression = "fast";
  std::string timings;  // "", "table" or "json"
  TextureFlags texture_flags;
  bool progress = false;
  BackendChoice backend;
};

// What happened about flipped triangles: the embedding's repair, refine's splits, the faces still flipped and why
// (input faces, or with refine the faces of the OBJ written anew).
void print_flip_notes(const mesh::MeshFile& file, const mesh::TextureMapping& mapping,
                      const mesh::MappingQuality& quality) {
  const mesh::TriangleMesh& mesh = file.mesh;
  if (mapping.embedding != proto::EmbeddingMethod::kLscm) {
    std::fprintf(stderr, "texwarp: map-mesh: the LSCM embedding flipped %zu triangles: replaced by the %s embedding\n",
                 mapping.lscm_flipped_faces.size(), proto::to_string(mapping.embedding));
  }
  // The counts of the refinement that was run (as the report's), the mesh of the one kept.
  if (const auto& r = mapping.refinement_counts; r && mapping.refinement) {
    const mesh::TriangleMesh& kept = mapping.refinement->mesh;
    std::fprintf(stderr,
                 "texwarp: map-mesh: refine: %d flipped UV triangles → %d (%s%s); %d features made vertices, %d edges "
                 "split in %d rounds: %d vertices, %d triangles (input %d, %d)\n",
                 r->flipped_before, r->flipped_after, proto::to_string(r->stop), r->kept ? "" : ", not kept",
                 r->feature_vertices, r->split_edges, r->rounds, kept.vertex_count(), kept.face_count(),
                 mesh.vertex_count(), mesh.face_count());
  }
  if (const auto& u = mapping.untangling) {
    std::fprintf(stderr, "texwarp: map-mesh: untangle: %d flipped UV triangles → %d in %d rounds%s\n",
                 u->result.rejected_before, u->result.rejected_after, u->result.rounds,
                 u->result.applied ? "" : " (not applied: no fewer)");
  }
  if (const auto& o = mapping.optimization) {
    if (o->applied) {
      std::fprintf(stderr,
                   "texwarp: map-mesh: optimize: L² stretch %.4g → %.4g, max σ1/σ2 %.4g → %.4g in %d iterations "
                   "(%zu vertices held)\n",
                   o->before.l2_stretch, quality.texture.l2_stretch, o->before.max_aspect, quality.texture.max_aspect,
                   o->result.iterations, o->fixed.size());
    } else {
      std::fprintf(stderr, "texwarp: map-mesh: optimize: skipped: %s\n", o->skipped.c_str());
    }
  }
  if (quality.flips.empty()) return;
  std::string faces;
  for (std::size_t i = 0; i < quality.flips.size() && i < 20; ++i) {
    const int face = mapping.refinement ? quality.flips[i].face : file.faces.of_triangle[quality.flips[i].face];
    faces += (i ? ", " : "") + std::to_string(face) + " (" + proto::to_string(quality.flips[i].cause) + ")";
  }
  if (quality.flips.size() > 20) faces += ", …";
  std::fprintf(stderr, "texwarp: map-mesh: flipped UV faces: %s%s\n", faces.c_str(),
               mapping.refinement ? "" : "; the warp bends inside them: refinement (not --no-refine) splits them");
}

Border border(const MapMeshArgs& args) {
  return proto::parse_enum<Border>(args.border, InputLocation::flag("--border"));
}

proto::GltfSelectionSpec gltf_selection(const MapMeshArgs& args) {
  proto::GltfSelectionSpec selection;
  selection.primitive = args.gltf_primitive;
  if (args.gltf_mesh.empty()) return selection;
  if (args.gltf_mesh.find_first_not_of("0123456789") == std::string::npos && args.gltf_mesh.size() <= 9) {
    selection.mesh_index = std::stoi(args.gltf_mesh);
  } else {
    selection.mesh_name = args.gltf_mesh;
  }
  return selection;
}

// --out-gltf writes a glTF mesh back, in its own container (.gltf or .glb).
void check_gltf_output(const MapMeshArgs& args, const mesh::MeshFile& file) {
  const InputLocation flag = InputLocation::flag("--out-gltf");
  if (!file.gltf) throw InputError(flag, "writes a glTF mesh back: --mesh must be a .gltf or .glb file");
  const std::string ext = std::filesystem::path(args.out_gltf).extension().string();
  const std::string want = file.gltf->binary ? ".glb" : ".gltf";
  if (ext != want) throw InputError(flag, "the mesh is a " + want + " file: name the output " + want + " too");
}

int run_map_mesh(const MapMeshArgs& args) {
  const InterruptCancel interrupts;  // SIGINT and SIGTERM cancel the work below: exit 3, nothing written
  using namespace texwarp::mesh;
  using proto::LatencyStage;
  // The stages in the order they run: the mapping, the warped textures' grid, then each map of the set read,
  // sampled, encoded and written (the textures' stages only when warped textures are wanted); every file is written
  // last.
  const bool texture = !args.out_texture.empty() || !args.out_dir.empty();
  // (Filtered from the full list rather than inserted: GCC 12 warns -Warray-bounds on a vector's insert of an
  // initializer list here, a false positive.)
  std::vector<LatencyStage> stages;
  for (const LatencyStage s : {LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup,
                               LatencyStage::kMapping, LatencyStage::kPathlines, LatencyStage::kDecode,
                               LatencyStage::kSampling, LatencyStage::kEncode, LatencyStage::kWrite}) {
    const bool texture_stage = s == LatencyStage::kDecode || s == LatencyStage::kPathlines ||
                               s == LatencyStage::kSampling || s == LatencyStage::kEncode;
    if (texture || !texture_stage) stages.push_back(s);
  }
  CommandClock clock(std::move(stages), args.progress);
  const auto start = std::chrono::steady_clock::now();
  const auto plan_start = start;
  const auto origin = proto::parse_enum<UvOrigin>(args.uv_origin, InputLocation::flag("--uv-origin"));

  const MeshFile file = read_mesh_document(args.mesh, gltf_selection(args));
  const TriangleMesh& mesh = file.mesh;
  if (!args.out_gltf.empty()) check_gltf_output(args, file);
  if (args.refine && file.gltf && !file.gltf->unrefinable.empty()) {
    throw InputError(InputLocation::flag("--refine"),
                     "this glTF primitive cannot take new vertices: " + file.gltf->unrefinable);
  }
  if (args.refine && args.no_refine) throw InputError(InputLocation::flag("--no-refine"), "contradicts --refine");
  std::optional<RegionSpec> region_spec;
  const InputLocation region_place = InputLocation::file(args.region.empty() ? args.mesh : args.region);
  if (!args.region.empty()) {
    const nlohmann::json j = read_json_file(args.region);
    region_spec = region_on_triangles(in_file(args.region, [&] { return proto::decode_region_spec(j); }), file.faces,
                                      region_place);
  }
  MeshRegion region = select_region(mesh, region_spec, region_place);
  // The mesh's own memory (flattening) against the budget first, with texwarpd's model (runner/mesh_memory.hpp).
  const std::uint64_t budget = memory_budget_from_mib(args.max_job_memory_mb, 1);
  std::error_code size_error;
  const std::uint64_t mesh_bytes = std::filesystem::file_size(args.mesh, size_error);
  // Refined by default where the output can take new faces: OBJ, JSON and glTF unless its vertex data is compressed.
  const bool refine = args.refine || (!args.no_refine && (!file.gltf || file.gltf->unrefinable.empty()));
  const runner::MeshSize mesh_size{static_cast<std::uint64_t>(mesh.face_count()), size_error ? 0 : mesh_bytes, false,
                                   file.gltf ? file.gltf->kept_bytes(refine) : 0};
  MemoryEstimate memory_estimate;
  memory_estimate.add_phase(runner::mesh_flattening(mesh_size));
  check_memory_budget(memory_estimate, budget, InputLocation::file(args.mesh), "--max-job-memory-mb");
  const nlohmann::json feature_json = read_json_file(args.features);
  const SurfaceFeatureSet features = in_file(args.features, [&] {
    return features_on_triangles(surface_features_from_spec(proto::decode_surface_feature_set(feature_json)),
                                 file.faces);
  });

  // The textures: their headers (the features are in their pixels: one size for all); the first map with an output
  // decoded while the mesh is mapped (PrefetchedSource below), the others when warped.
  SetFlags set_flags;
  set_flags.in = "--texture";
  set_flags.out = "--out-texture";
  set_flags.udim = false;
  set_flags.output_required = false;
  std::optional<PixelFormat> asked_format;
  if (!args.format.empty()) asked_format = proto::parse_enum<PixelFormat>(args.format, InputLocation::flag("--format"));
  const std::vector<SetMap> maps = plan_set_maps(args.textures, args.out_texture, args.out_dir, asked_format,
                                                 args.texture_flags, border(args), set_flags);
  // Outputs that cannot be written fail now, not after the mapping.
  check_set_outputs(maps, args.out_dir, set_flags);
  check_output_file("--out-obj", args.out_obj);
  check_output_file("--out-gltf", args.out_gltf);
  check_output_file("--report", args.report);
  const ImageHeader header = maps.front().header;
  const SamplingFilter filter = texture_filter(args.texture_flags);
  const auto prefetched = prefetched_map(maps);
  if (texture) {
    // What the warped textures will allocate, from the headers, before any pixel is decoded.
    const auto memory_of = [&](const SetMap& map) {
      ImageWarpMemoryInput memory = set_map_memory(maps, map, args.width, args.height, border(args), filter);
      memory.resident = runner::mesh_resident(mesh_size);
      return memory;
    };
    MemoryEstimate with_texture = check_set_memory(maps, memory_of, budget, "", "--max-job-memory-mb");
    // Each phase is checked where it is made (the flattening above, each map's in check_set_memory, naming that
    // map): the peak is the largest phase. The flattening has the prefetched map's decode beside it (checked here,
    // naming that map).
    MemoryPhase flattening = runner::mesh_flattening(mesh_size);
    if (prefetched != maps.end()) {
      const MemoryPhase decoding = decoding_buffers(memory_of(*prefetched));
      flattening.insert(flattening.end(), decoding.begin(), decoding.end());
      MemoryEstimate beside;
      beside.add_phase(flattening);
      check_memory_budget(beside, budget, InputLocation::file(prefetched->input.path), "--max-job-memory-mb");
    }
    with_texture.add_phase(std::move(flattening));
    memory_estimate = with_texture;
  }
  runner::StageWorkload workload =
      runner::image_workload(header, args.width, args.height, features.features.size(), false);
  workload.maps = static_cast<std::size_t>(std::max<std::ptrdiff_t>(
      1, std::count_if(maps.begin(), maps.end(), [](const SetMap& m) { return !m.output.empty(); })));
  clock.set_workload(workload);
  clock.add(LatencyStage::kPlan, std::chrono::duration<double>(std::chrono::steady_clock::now() - plan_start).count());

  TextureMappingOptions options;
  options.texture_width = header.width;
  options.texture_height = header.height;
  options.frame_width = args.width;
  options.frame_height = args.height;
  options.margin_px = args.margin_px;
  options.refine = refine;
  options.optimize = proto::parse_enum<proto::UvOptimize>(args.optimize, InputLocation::flag("--optimize"));
  // Refinement adds vertices only as far as the budget leaves room once the unrefined command fits.
  options.max_refined_vertices =
      runner::refined_vertex_budget(budget, memory_estimate.peak_bytes(), region.vertex_count());
  // The first map is decoded while the device is set up and the mesh mapped.
  std::optional<PrefetchedSource> first_source;
  if (texture) first_source.emplace(maps, border(args), false);
  auto backend = clock.time(LatencyStage::kDeviceSetup, [&] { return make_backend(args.backend); });
  RunControl control;
  control.threads = args.backend.threads;
  control.cancel = interrupts.flag();
  control.progress = clock.progress_within(LatencyStage::kMapping);

  const TextureMapping mapping = clock.time(LatencyStage::kMapping, [&] {
    return in_file(args.features,
                   [&] { return map_texture(*backend, mesh, std::move(region), features, options, control); });
  });
  const MappingQuality quality = clock.time(LatencyStage::kMapping, [&] {
    return evaluate_mapping(mesh, mapping, mapping.texture_px, options, args.per_triangle);
  });
  // "N region faces", and their triangles when a face is a polygon.
  const int faces = region_face_count(mapping.region.faces, file.faces, mapping.refinement.has_value());
  const std::string region_faces =
      std::to_string(faces) + " region faces" +
      (faces != mapping.region.face_count() ? " (" + std::to_string(mapping.region.face_count()) + " triangles)" : "");

  // The warped textures first, then the files: a warp that fails leaves no mesh file behind.
  std::vector<WrittenSetMap> written_maps;
  if (texture) {
    SetWarp warp;
    warp.options.width = mapping.frame_width;
    warp.options.height = mapping.frame_height;
    warp.options.interpolation = proto::parse_enum<Interpolation>(args.interpolation, InputLocation::flag("--interp"));
    warp.options.border = border(args);
    warp.options.filter = filter;
    warp.encoding.png_compression_level = args.png_level;
    warp.encoding.compression = proto::parse_enum<Compression>(args.compression, InputLocation::flag("--compression"));
    warp.control.threads = args.backend.threads;
    warp.control.cancel = interrupts.flag();
    RunControl grid_control = control;
    grid_control.progress = clock.progress_within(LatencyStage::kPathlines);
    const bool positions_needed = std::any_of(maps.begin(), maps.end(), [](const SetMap& m) {
      return !m.output.empty() && m.encoding.role == ImageRole::kNormal;
    });
    const OutputGridMap grid = map_output_grid(*backend, *mapping.problem, header.width, header.height, warp.options,
                                               positions_needed, grid_control, false);
    clock.add(LatencyStage::kPathlines, grid.map_s);
    warp.folder = args.out_dir;
    written_maps = warp_set_maps(grid, maps, warp, clock, first_source ? &*first_source : nullptr);
  }
  // The warped texture the mesh's UVs point into with --obj-uv warped: the one written, or a set's first colour map.
  std::string warped_texture;
  for (const WrittenSetMap& m : written_maps) {
    if (written_maps.size() == 1 || m.report.output.sampling->role == ImageRole::kColor) {
      warped_texture = m.report.output.file;
      break;
    }
  }

  // The region's UVs the mesh outputs carry: into the warped texture (--obj-uv warped) or the original one.
  const bool warped =
      proto::parse_enum<proto::ObjUv>(args.obj_uv, InputLocation::flag("--obj-uv")) == proto::ObjUv::kWarped;
  const auto region_uvs = [&](UvOrigin uv_origin) {
    std::vector<std::array<double, 2>> uvs;
    uvs.reserve(mapping.texture_px.size());
    for (int i = 0; i < mapping.region.vertex_count(); ++i) {
      uvs.push_back(warped ? pixel_to_uv(mapping.frame.pixels[i], mapping.frame_width, mapping.frame_height, uv_origin)
                           : pixel_to_uv(mapping.texture_px[i], header.width, header.height, uv_origin));
    }
    return uvs;
  };
  if (!args.out_obj.empty()) {
    const std::vector<std::array<double, 2>> uvs = region_uvs(origin);
    // An OBJ's own lines are kept unless refinement added vertices and faces (then it is written anew).
    const bool keep_lines = file.format == proto::MeshFormat::kObj && !mapping.refinement;
    const std::string comment =
        "texwarp map-mesh: " + region_faces + " textured, " + std::to_string(mapping.features.size()) + " features\n" +
        "uv_origin " + to_string(origin) + "; UVs into " +
        (warped
             ? (written_maps.size() > 1
                    ? "the warped textures in " + args.out_dir
                    : "the warped texture " + (warped_texture.empty() ? std::string("(not written)") : warped_texture))
             : "the original texture " + maps.front().input.path) +
        (keep_lines ? "\nthe input's lines kept; the region's faces point at the vt lines at the end"
                    : "\nvt per region vertex; faces outside the region have no vt") +
        (mapping.refinement ? "\nrefined: vertices past the input's " + std::to_string(mesh.vertex_count()) +
                                  " and faces past its " + std::to_string(mesh.face_count()) +
                                  " are new (the report's refinement, triangles and vertices map them back)"
                            : std::string());
    clock.time(LatencyStage::kWrite, [&] {
      write_text_file_atomically(
          args.out_obj, keep_lines
                            ? textured_obj_text(file.obj_text, mesh, file.faces, mapping.region, uvs, comment)
                            : textured_obj_text(output_mesh(mesh, mapping.refinement), mapping.region, uvs, comment));
    });
  }
  if (!args.out_gltf.empty()) {
    // glTF's top-left origin whatever --uv-origin; the warped texture as base colour when the UVs point into it.
    const std::vector<std::array<double, 2>> uvs = region_uvs(UvOrigin::kTopLeft);
    std::optional<std::string> base_color;
    if (warped && !warped_texture.empty()) {
      const std::filesystem::path folder = std::filesystem::absolute(args.out_gltf).parent_path();
      base_color = std::filesystem::absolute(warped_texture).lexically_relative(folder).generic_string();
    }
    clock.time(LatencyStage::kWrite, [&] {
      write_text_file_atomically(args.out_gltf,
                                 textured_gltf_bytes(*file.gltf, mapping.region, uvs, base_color,
                                                     mapping.refinement ? &*mapping.refinement : nullptr));
    });
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!args.report.empty()) {
    MappingReportOptions report;
    report.uv_origin = origin;
    report.per_triangle = args.per_triangle;
    report.per_vertex = args.per_vertex;
    report.total_seconds = seconds;
    clock.time(LatencyStage::kWrite, [&] {
      proto::MeshMappingReport typed = mesh_mapping_report(mesh, mapping, quality, options, report);
      if (!written_maps.empty()) typed.texture_sampling = written_maps.front().report.output.sampling;
      if (written_maps.size() > 1) {
        typed.maps.emplace();
        for (const WrittenSetMap& m : written_maps) typed.maps->push_back(m.report);
      }
      name_input_faces(typed, file.faces, mapping.region.faces);
      write_text_file_atomically(args.report, proto::encode_mesh_mapping_report(typed).dump(2) + "\n");
    });
  }
  clock.finish(args.timings);
  std::fprintf(stderr,
               "texwarp: map-mesh: %s, %zu features on %s in %.2f s; L2 stretch %.4g, L2 shear %.4g, "
               "%d flipped triangles, max residual %.3g px\n",
               region_faces.c_str(), mapping.features.size(), backend->name().c_str(), seconds,
               quality.texture.l2_stretch, quality.texture.l2_shear, quality.texture.flipped, quality.max_residual_px);
  say_double_retries(*backend, "map-mesh");
  for (const WrittenSetMap& m : written_maps) std::fprintf(stderr, "texwarp: map-mesh: %s\n", m.summary.c_str());
  print_flip_notes(file, mapping, quality);
  return kExitOk;
}

}  // namespace

void add_map_mesh_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<MapMeshArgs>();
  CLI::App* cmd = root.add_subcommand(
      "map-mesh", "Texture a region of a mesh so that texture features land on surface features (LSCM + warp)");
  cmd->add_option("--mesh", args->mesh,
                  R"(mesh: .obj (triangles, quads, n-gons), .json {"vertices", "triangles"}, .gltf or .glb)")
      ->required();
  cmd->add_option("--gltf-mesh", args->gltf_mesh, "glTF: the mesh to texture, by name or index (default: mesh 0)");
  cmd->add_option("--gltf-primitive", args->gltf_primitive, "glTF: the mesh's primitive to texture (default 0)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--texture", args->textures,
                  "texture image (feature sources are in its pixels), as PATH or ROLE=PATH (ROLE color, data or "
                  "normal, as `texwarp warp --in`); repeat it for the maps of a texture set (same size): the warp's "
                  "map is computed once and each map sampled with its role")
      ->required();
  cmd->add_option("--features", args->features, "surface feature file (JSON)")->required();
  cmd->add_option("--region", args->region,
                  "region file {\"faces\": [...]} or {\"boundary\": [...], \"seed_face\": f} (default: the whole "
                  "mesh, which must then be a disk)");
  cmd->add_option("--out-obj", args->out_obj,
                  "output OBJ: an OBJ mesh's lines kept, its region's faces pointing at new vt lines (other meshes: "
                  "vertices in order, vt and f v/vt for the region)");
  cmd->add_option("--out-gltf", args->out_gltf,
                  "output glTF (a .gltf/.glb mesh only, same container): TEXCOORD_0 = the new UVs, top-left origin");
  cmd->add_option("--out-texture", args->out_texture,
                  "output warped texture of a single --texture (format from the extension)");
  cmd->add_option("--out-dir", args->out_dir,
                  "output folder of the warped textures of any number of --texture: each keeps its input's file name "
                  "(and format); a glTF's base colour is the first colour map");
  cmd->add_option("--report", args->report, "output report (JSON)");
  cmd->add_option("--uv-origin", args->uv_origin, "bottom_left (default; OBJ, DCC tools) or top_left (glTF)")
      ->check(CLI::IsMember(proto::enum_names<proto::UvOrigin>()));
  cmd->add_option("--obj-uv", args->obj_uv,
                  "UVs written to the OBJ: original (default; into --texture) or warped (into the warped texture, a "
                  "set's first colour map)")
      ->check(CLI::IsMember(proto::enum_names<proto::ObjUv>()));
  cmd->add_option("--margin", args->margin_px,
                  "free band around the embedding in the warped texture, pixels (default 8)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--width", args->width, "warped texture width in pixels (default: the texture's)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--height", args->height, "warped texture height in pixels (default: the texture's)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--interp", args->interpolation, "warped texture sampling: bilinear (default) or bicubic")
      ->check(CLI::IsMember(proto::enum_names<Interpolation>()));
  cmd->add_option("--border", args->border, "outside the texture: transparent (default), clamp or repeat")
      ->check(CLI::IsMember(proto::enum_names<Border>()));
  cmd->add_option("--format", args->format, "warped texture pixel type: uint8|uint16|half|float (default: the input's)")
      ->check(CLI::IsMember(proto::enum_names<PixelFormat>()));
  cmd->add_flag("--per-triangle", args->per_triangle, "report: stretch and shear of every region triangle");
  cmd->add_flag("--per-vertex", args->per_vertex, "report: both UVs of every region vertex");
  cmd->add_flag(
      "--refine", args->refine,
      "split the triangles whose UVs flip until none does, and the faces at features (they become exact "
      "vertices); new vertices and faces follow the input's in the OBJ or glTF (their attributes interpolated) "
      "and map back to input faces in the report (the default, but for a glTF primitive whose vertex data is "
      "compressed)");
  cmd->add_flag("--no-refine", args->no_refine, "keep the input's faces: UV triangles the warp flips stay flipped");
  cmd->add_option("--optimize", args->optimize,
                  "stretch (default): lower the UVs' distortion from the warp's flip-free UVs, pins fixed, never "
                  "through a flip; none: the warp's UVs")
      ->check(CLI::IsMember(proto::enum_names<proto::UvOptimize>()));
  cmd->add_option("--max-job-memory-mb", args->max_job_memory_mb,
                  "refuse a mesh or warped texture estimated to need more memory than this, MiB (default: half the "
                  "machine's memory); refinement adds vertices only within it");
  cmd->add_option("--png-level", args->png_level, "zlib level of a PNG warped texture: 0 to 9 (default 1, fastest)")
      ->check(CLI::Range(0, proto::kMaxPngCompressionLevel));
  cmd->add_option("--compression", args->compression, "TIFF and EXR warped texture: fast (default), none or small")
      ->check(CLI::IsMember(proto::enum_names<Compression>()));
  add_progress_option(*cmd, args->progress);
  add_timings_option(*cmd, args->timings);
  add_texture_options(*cmd, args->texture_flags);
  add_backend_options(*cmd, args->backend);
  cmd->callback([args, &action] { action = [args] { return run_map_mesh(*args); }; });
}

}  // namespace texwarp::cli
