// Running a mesh job's plan: LSCM, surface features and the warp's problem (mesh::map_texture), the textured OBJ
// (or glTF) and uvs.json, the warped texture when asked for, and the report (the mesh mapping report plus the job's
// fields).
#include <array>
#include <vector>

#include "input_place.hpp"
#include "job_runs.hpp"
#include "texwarp/core/closed_form_warp.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/gltf_output.hpp"
#include "texwarp/mesh/input_faces.hpp"
#include "texwarp/mesh/mapping_report.hpp"
#include "texwarp/mesh/obj_output.hpp"

namespace texwarp::runner {
namespace {

namespace fs = std::filesystem;

struct MeshUvs {
  std::vector<std::array<double, 2>> texture;  // per region vertex, into the original texture
  std::vector<std::array<double, 2>> warped;   // into the warped texture
};

MeshUvs mesh_uvs(const JobPlan& plan, const mesh::TextureMapping& mapping) {
  const mesh::UvOrigin origin = plan.mesh->uv_origin;
  MeshUvs uvs;
  for (int i = 0; i < mapping.region.vertex_count(); ++i) {
    uvs.texture.push_back(mesh::pixel_to_uv(mapping.texture_px[i], plan.header.width, plan.header.height, origin));
    uvs.warped.push_back(mesh::pixel_to_uv(mapping.frame.pixels[i], mapping.frame_width, mapping.frame_height, origin));
  }
  return uvs;
}

// With `refine`: how the OBJ's new vertices and faces map back to the input mesh.
std::string refined_obj_comment(const mesh::TextureMapping& mapping) {
  if (!mapping.refinement) return {};
  const mesh::MeshRefinement& r = *mapping.refinement;
  return "\nrefined: vertices from " + std::to_string(r.input_vertices + 1) + " and faces from " +
         std::to_string(r.input_faces + 1) + " (1-based) are new; uvs.json maps them to input faces " +
         "(source_face, new_vertices)";
}

// The warped textures the UVs point into: the image file, or a set's files ("a.png, b.png and c.exr").
std::string warped_files_text(const JobPlan& plan) {
  std::string text;
  for (std::size_t i = 0; i < plan.maps.size(); ++i) {
    if (i > 0) text += i + 1 == plan.maps.size() ? " and " : ", ";
    text += plan.maps[i].image_file;
  }
  return text;
}

// The glTF material's base colour: the warped image, or a set's first colour map (none without one).
std::optional<std::string> base_color_file(const JobPlan& plan) {
  if (!plan.spec->is_set()) return plan.image_file;
  for (const PlannedMap& map : plan.maps) {
    if (map.encoding.role == ImageRole::kColor) return map.image_file;
  }
  return std::nullopt;
}

// mesh.obj (vt per region vertex, into the original or the warped texture; an OBJ's own lines kept unless refined),
// or the glTF written back (mesh.gltf / mesh.glb), and uvs.json (both).
std::vector<JobFile> write_mesh_files(const JobPlan& plan, const mesh::TextureMapping& mapping,
                                      const fs::path& out_dir) {
  const proto::MeshJobSpec& m = *plan.spec->mesh;
  const std::string origin = to_string(plan.mesh->uv_origin);
  const MeshUvs uvs = mesh_uvs(plan, mapping);
  // An OBJ's own lines are kept unless refinement added vertices and faces (then it is written anew).
  const bool keep_lines = plan.mesh->file.format == proto::MeshFormat::kObj && !mapping.refinement;
  const int faces =
      mesh::region_face_count(mapping.region.faces, plan.mesh->file.faces, mapping.refinement.has_value());
  const std::string comment =
      "texwarp mesh job: " + std::to_string(faces) + " region faces" +
      (faces != mapping.region.face_count() ? " (" + std::to_string(mapping.region.face_count()) + " triangles)" : "") +
      " textured, " + std::to_string(mapping.features.size()) + " features\nuv_origin " + origin + "; UVs into " +
      (m.obj_uv == proto::ObjUv::kWarped
           ? (plan.maps.size() > 1 ? "the warped textures " : "the warped texture ") + warped_files_text(plan)
           : std::string("the original texture")) +
      (keep_lines ? "\nthe input's lines kept; the region's faces point at the vt lines at the end"
                  : "\nvt per region vertex; faces outside the region have no vt") +
      refined_obj_comment(mapping);
  const bool warped = m.obj_uv == proto::ObjUv::kWarped;
  std::vector<JobFile> files;
  const mesh::MeshFile& file = plan.mesh->file;
  if (file.gltf) {
    // glTF: TEXCOORD_0 with glTF's top-left origin whatever the job's uv_origin; the warped texture becomes the
    // primitive's baseColorTexture when the job writes it and the UVs point into it.
    std::vector<std::array<double, 2>> top_left;
    top_left.reserve(static_cast<std::size_t>(mapping.region.vertex_count()));
    for (int i = 0; i < mapping.region.vertex_count(); ++i) {
      top_left.push_back(warped ? mesh::pixel_to_uv(mapping.frame.pixels[i], mapping.frame_width, mapping.frame_height,
                                                    mesh::UvOrigin::kTopLeft)
                                : mesh::pixel_to_uv(mapping.texture_px[i], plan.header.width, plan.header.height,
                                                    mesh::UvOrigin::kTopLeft));
    }
    const std::optional<std::string> base_color =
        warped && plan.spec->output.image ? base_color_file(plan) : std::nullopt;
    const char* name = file.gltf->binary ? kGlbFile : kGltfFile;
    write_text_file_atomically((out_dir / name).string(),
                               mesh::textured_gltf_bytes(*file.gltf, mapping.region, top_left, base_color,
                                                         mapping.refinement ? &*mapping.refinement : nullptr));
    files.push_back({name, media_type_for(name)});
  } else {
    const auto& obj_uvs = warped ? uvs.warped : uvs.texture;
    write_text_file_atomically(
        (out_dir / kObjFile).string(),
        keep_lines
            ? mesh::textured_obj_text(file.obj_text, *plan.mesh->mesh, file.faces, mapping.region, obj_uvs, comment)
            : mesh::textured_obj_text(mesh::output_mesh(*plan.mesh->mesh, mapping.refinement), mapping.region, obj_uvs,
                                      comment));
    files.push_back({kObjFile, media_type_for(kObjFile)});
  }
  nlohmann::json uv_doc = {{"uv_origin", origin},
                           {"texture", {{"width", plan.header.width}, {"height", plan.header.height}}},
                           {"warped_texture", {{"width", mapping.frame_width}, {"height", mapping.frame_height}}},
                           {"vertices", mapping.region.vertices},
                           {"uv", uvs.texture},
                           {"warped_uv", uvs.warped}};
  if (const auto& refined = mapping.refinement) {
    // Input faces, as the report names them (a quad's or n-gon's triangles all name it).
    std::vector<int> source_face;
    for (const int t : refined->source_face) source_face.push_back(file.faces.of_triangle[t]);
    uv_doc["source_face"] = std::move(source_face);
    nlohmann::json added = nlohmann::json::array();
    for (const mesh::SurfacePoint& p : refined->new_vertices) {
      // The weights are on one triangle of the face (a quad's or n-gon's): its input vertices, in their order.
      const mesh::Face& corners = plan.mesh->mesh->faces[p.face];
      added.push_back({{"face", file.faces.of_triangle[p.face]},
                       {"barycentric", p.barycentric},
                       {"corners", {corners[0], corners[1], corners[2]}}});
    }
    uv_doc["new_vertices"] = {{"first", refined->input_vertices}, {"source", std::move(added)}};
  }
  write_text_file_atomically((out_dir / kUvFile).string(), uv_doc.dump() + "\n");
  files.push_back({kUvFile, media_type_for(kUvFile)});
  return files;
}

struct MappedMesh {
  mesh::TextureMapping mapping;
  mesh::MappingQuality quality;
};

// LSCM, the surface features placed and the warp's problem (InputError under $.mesh.features), and the quality
// of the UVs. Takes over the plan's region.
MappedMesh map_mesh(MeshPlan& m, WarpBackend& backend, const proto::JobSpec& spec, const RunControl& control) {
  mesh::TextureMapping mapping = at_path(JsonPath{"mesh", "features"}, [&] {
    return mesh::map_texture(backend, *m.mesh, std::move(*m.selected), m.features, m.mapping,
                             phase(control, 0.05, 0.3));
  });
  mesh::MappingQuality quality =
      mesh::evaluate_mapping(*m.mesh, mapping, mapping.texture_px, m.mapping, spec.mesh->per_triangle);
  return {std::move(mapping), std::move(quality)};
}

}  // namespace

JobOutput run_mesh_plan(JobPlan&& plan, BackendCache& backends, const fs::path& out_dir, const JobLimits& limits,
                        const RunControl& control, Clock::time_point start) {
  const proto::JobSpec& spec = *plan.spec;
  MeshPlan& m = *plan.mesh;
  proto::JobReport report;
  proto::StageTimings& stages = report.timings.stages;
  report.timings.mesh_s = m.load_seconds;
  stages.add(proto::LatencyStage::kPlan, plan.seconds);
  const auto device_start = Clock::now();
  WarpBackend& backend = backends.get(spec.options.device);
  const std::uint64_t retries_before = backend.double_retries();
  stages.add(proto::LatencyStage::kDeviceSetup, seconds_since(device_start));
  report_progress(control, 0.05);
  // Named members, not a structured binding: clang 14 (clang-tidy's) does not let a lambda capture a binding.
  const MappedMesh mapped = timed(report.timings.mapping_s, [&] { return map_mesh(m, backend, spec, control); });
  const mesh::TextureMapping& mapping = mapped.mapping;
  const mesh::MappingQuality& quality = mapped.quality;
  stages.add(proto::LatencyStage::kMapping, *report.timings.mapping_s);
  report_progress(control, 0.32);
  const auto files_start = Clock::now();
  std::vector<JobFile> files = write_mesh_files(plan, mapping, out_dir);
  stages.add(proto::LatencyStage::kWrite, seconds_since(files_start));
  report.method = proto::WarpMethodReport::kNone;
  std::optional<WarpedMaps> maps;
  if (spec.output.image) {
    // The frame's map once, every map of the job sampled through it (a texture set: one after another).
    timed(report.timings.warp_s, [&] {
      ImageWarpOptions warp = plan.warp;
      warp.width = mapping.frame_width;
      warp.height = mapping.frame_height;
      const OutputGridMap grid = map_output_grid(backend, *mapping.problem, plan.header.width, plan.header.height, warp,
                                                 positions_needed(plan), phase(control, 0.32, 0.6));
      stages.add(proto::LatencyStage::kPathlines, grid.map_s);
      maps = warp_maps(plan, grid, warp, false, out_dir, limits, phase(control, 0.6, 0.97), stages);
      report.timings.read_s = maps->read_s;
      for (JobFile& f : maps->files) files.push_back(std::move(f));
      record_warp(report, grid.certificate, has_closed_form(*mapping.problem));
    });
  }
  report_progress(control, 0.98);
  mesh::MappingReportOptions report_options;
  report_options.uv_origin = m.uv_origin;
  report_options.per_triangle = spec.mesh->per_triangle;
  report_options.per_vertex = spec.mesh->per_vertex;
  report.mesh = mesh::mesh_mapping_report(*m.mesh, mapping, quality, m.mapping, report_options);
  mesh::name_input_faces(*report.mesh, m.file.faces, mapping.region.faces);
  if (maps) {
    report.mesh->texture_sampling = maps->reports.front().output.sampling;
    if (spec.is_set()) report.mesh->maps = std::move(maps->reports);
  }
  report.backend = backend.name();
  report.double_retries = backend.double_retries() - retries_before;
  report.exact = spec.options.exact;
  return finish_job(out_dir, std::move(files), std::move(report), start, control);
}

}  // namespace texwarp::runner
