// The mesh mapping report: see mapping_report.hpp.
#include "texwarp/mesh/mapping_report.hpp"

#include "texwarp/core/warp_problem_report.hpp"
#include "texwarp/proto/job_report_codec.hpp"

namespace texwarp::mesh {
namespace {

std::array<double, 2> point_array(Point p) { return {p.real(), p.imag()}; }

proto::UvQualityReport uv_quality(const UvMetrics& m) {
  return {m.l2_stretch, m.linf_stretch, m.l2_shear, m.flipped, m.degenerate, m.max_aspect};
}

}  // namespace

proto::MeshMappingReport mesh_mapping_report(const TriangleMesh& mesh, const TextureMapping& mapping,
                                             const MappingQuality& quality, const TextureMappingOptions& options,
                                             const MappingReportOptions& report) {
  const MeshRegion& region = mapping.region;
  proto::MeshMappingReport r;
  r.uv_origin = report.uv_origin;
  // Faces as triangles until name_input_faces names the input's.
  r.mesh = {mesh.vertex_count(), mesh.face_count(), mesh.face_count()};
  r.region = {region.face_count(), region.vertex_count(), region.boundary.size(), region.face_count()};
  r.texture = {options.texture_width, options.texture_height};
  r.warped_texture = {mapping.frame_width, mapping.frame_height};
  r.lscm = {{region.vertices[mapping.lscm.pinned[0]], region.vertices[mapping.lscm.pinned[1]]},
            mapping.lscm.energy,
            mapping.frame.pixels_per_unit,
            mapping.lscm_seconds};
  r.warp = warp_setup_report(*mapping.problem);
  r.trajectory = trajectory_report(*mapping.problem);
  r.warp.features = mapping.features.size();
  r.warp.gradient_features = 0;
  for (const auto& p : mapping.features) r.warp.gradient_features += p.feature.is_gradient() ? 1 : 0;
  r.warp.vertex_seconds = mapping.warp_seconds;

  // The result: UVs into the original texture.
  r.uvs = uv_quality(quality.texture);
  r.max_residual_px = quality.max_residual_px;
  r.mean_residual_px = quality.mean_residual_px;
  r.vertices_outside_texture = quality.vertices_outside_texture;
  r.warped_uvs = uv_quality(quality.frame);
  if (report.total_seconds > 0.0) r.seconds = report.total_seconds;

  for (std::size_t i = 0; i < mapping.features.size(); ++i) {
    const PlacedFeature& p = mapping.features[i];
    proto::PlacedFeatureReport f;
    f.index = i;
    if (!p.feature.id.empty()) f.id = p.feature.id;
    f.face = p.location.face;
    f.barycentric = p.location.barycentric;
    f.position = {p.position.x, p.position.y, p.position.z};
    f.source = point_array(p.feature.source);
    f.target_px = point_array(p.feature.target);
    f.gradient = p.feature.is_gradient();
    f.residual_px = quality.residual_px[i];
    if (p.snap_distance > 0.0) f.snap_distance = p.snap_distance;
    r.features.push_back(std::move(f));
  }

  if (report.per_triangle && !quality.texture.per_triangle.empty()) {
    r.triangles.emplace();
    for (int i = 0; i < region.face_count(); ++i) {
      const TriangleDistortion& d = quality.texture.per_triangle[i];
      r.triangles->push_back(
          {region.faces[i], d.l2_stretch, d.linf_stretch, d.shear, d.flipped, d.degenerate, std::nullopt});
      if (mapping.refinement) r.triangles->back().source_face = mapping.refinement->source_face[region.faces[i]];
    }
  }
  if (report.per_vertex) {
    r.vertices.emplace();
    for (int i = 0; i < region.vertex_count(); ++i) {
      r.vertices->push_back(
          {region.vertices[i],
           pixel_to_uv(mapping.texture_px[i], options.texture_width, options.texture_height, report.uv_origin),
           pixel_to_uv(mapping.frame.pixels[i], mapping.frame_width, mapping.frame_height, report.uv_origin),
           std::nullopt});
      const int added = mapping.refinement ? region.vertices[i] - mapping.refinement->input_vertices : -1;
      if (added >= 0) {
        const SurfacePoint& s = mapping.refinement->new_vertices[added];
        const Face& corners = mesh.faces[s.face];  // the input triangle the weights are on
        r.vertices->back().source =
            proto::SourcePointReport{s.face, s.barycentric, std::array<int, 3>{corners[0], corners[1], corners[2]}};
      }
    }
  }
  r.embedding = proto::EmbeddingReport{mapping.embedding, mapping.lscm_flipped_faces};
  r.flips.emplace();
  for (const FlippedFace& f : quality.flips) {
    proto::FlippedFaceReport flip;
    flip.face = f.face;
    if (mapping.refinement) flip.source_face = mapping.refinement->source_face[f.face];
    flip.cause = f.cause;
    r.flips->push_back(flip);
  }
  if (const auto& refined = mapping.refinement_counts) {
    proto::RefinementReport& x = r.refinement.emplace();
    x.feature_vertices = refined->feature_vertices;
    x.split_edges = refined->split_edges;
    x.rounds = refined->rounds;
    const TriangleMesh& out = output_mesh(mesh, mapping.refinement);
    x.output_vertices = out.vertex_count();
    x.output_faces = out.face_count();
    x.added_vertices = x.output_vertices - refined->input_vertices;
    x.added_faces = x.output_faces - refined->input_faces;
    x.flipped_before = refined->flipped_before;
    x.flipped_after = refined->flipped_after;
    x.vertex_limit = refined->vertex_limit;
    x.stop = refined->stop;
    x.kept = refined->kept;
    x.seconds = mapping.refinement_seconds;
  }
  if (const auto& u = mapping.untangling) {
    proto::UvUntanglingReport& x = r.untangling.emplace();
    x.applied = u->result.applied;
    x.flipped_before = u->result.rejected_before;
    x.flipped_after = u->result.rejected_after;
    x.rounds = u->result.rounds;
    x.seconds = u->seconds;
  }
  if (const auto& o = mapping.optimization) {
    proto::UvOptimizationReport& x = r.optimization.emplace();
    x.method = proto::UvOptimize::kStretch;
    x.applied = o->applied;
    if (!o->applied) x.skipped = o->skipped;
    x.iterations = o->result.iterations;
    x.converged = o->result.converged;
    x.energy_before = o->result.energy_before;
    x.energy_after = o->result.energy_after;
    x.before = uv_quality(o->before);
    x.seconds = o->seconds;
  }
  return r;
}

nlohmann::json mapping_report(const TriangleMesh& mesh, const TextureMapping& mapping, const MappingQuality& quality,
                              const TextureMappingOptions& options, const MappingReportOptions& report) {
  return proto::encode_mesh_mapping_report(mesh_mapping_report(mesh, mapping, quality, options, report));
}

}  // namespace texwarp::mesh
