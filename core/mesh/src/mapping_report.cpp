// The map-mesh report: see mapping_report.hpp.
#include "texwarp/mesh/mapping_report.hpp"

namespace texwarp::mesh {
namespace {

nlohmann::json point_json(Point p) { return nlohmann::json::array({p.real(), p.imag()}); }

nlohmann::json metrics_json(const UvMetrics& m) {
  return {{"l2_stretch", m.l2_stretch},       {"linf_stretch", m.linf_stretch},
          {"l2_shear", m.l2_shear},           {"flipped_triangles", m.flipped},
          {"degenerate_triangles", m.degenerate}};
}

}  // namespace

nlohmann::json mapping_report(const TriangleMesh& mesh, const TextureMapping& mapping, const MappingQuality& quality,
                              const TextureMappingOptions& options, const MappingReportOptions& report) {
  const MeshRegion& region = mapping.region;
  const WarpProblem& problem = *mapping.problem;
  nlohmann::json j;
  j["uv_origin"] = to_string(report.uv_origin);
  j["mesh"] = {{"vertices", mesh.vertex_count()}, {"faces", mesh.face_count()}};
  j["region"] = {{"faces", region.face_count()},
                 {"vertices", region.vertex_count()},
                 {"boundary_vertices", region.boundary.size()}};
  j["texture"] = {{"width", options.texture_width}, {"height", options.texture_height}};
  j["warped_texture"] = {{"width", mapping.frame_width}, {"height", mapping.frame_height}};
  j["lscm"] = {{"pinned_vertices", {region.vertices[mapping.lscm.pinned[0]], region.vertices[mapping.lscm.pinned[1]]}},
               {"energy", mapping.lscm.energy},
               {"frame_pixels_per_unit", mapping.frame.pixels_per_unit},
               {"seconds", mapping.lscm_seconds}};
  std::size_t gradients = 0;
  for (const auto& p : mapping.features) gradients += p.feature.is_gradient() ? 1 : 0;
  j["warp"] = {{"alpha", problem.alpha()},
               {"prealign", problem.options().prealign == Prealign::kSimilarity ? "similarity" : "none"},
               {"tolerance_px", problem.tolerance_px()},
               {"features", mapping.features.size()},
               {"gradient_features", gradients},
               {"vertex_seconds", mapping.warp_seconds}};

  // The result: UVs into the original texture.
  j["l2_stretch"] = quality.texture.l2_stretch;
  j["linf_stretch"] = quality.texture.linf_stretch;
  j["l2_shear"] = quality.texture.l2_shear;
  j["flipped_triangles"] = quality.texture.flipped;
  j["degenerate_triangles"] = quality.texture.degenerate;
  j["max_residual_px"] = quality.max_residual_px;
  j["mean_residual_px"] = quality.mean_residual_px;
  j["vertices_outside_texture"] = quality.vertices_outside_texture;
  j["warped_uvs"] = metrics_json(quality.frame);
  if (report.total_seconds > 0.0) j["seconds"] = report.total_seconds;

  nlohmann::json features = nlohmann::json::array();
  for (std::size_t i = 0; i < mapping.features.size(); ++i) {
    const PlacedFeature& p = mapping.features[i];
    nlohmann::json f = {{"index", i},
                        {"face", p.location.face},
                        {"barycentric", p.location.barycentric},
                        {"position", {p.position.x, p.position.y, p.position.z}},
                        {"source", point_json(p.feature.source)},
                        {"target_px", point_json(p.feature.target)},
                        {"gradient", p.feature.is_gradient()},
                        {"residual_px", quality.residual_px[i]}};
    if (!p.feature.id.empty()) f["id"] = p.feature.id;
    if (p.snap_distance > 0.0) f["snap_distance"] = p.snap_distance;
    features.push_back(std::move(f));
  }
  j["features"] = std::move(features);

  if (report.per_triangle && !quality.texture.per_triangle.empty()) {
    nlohmann::json triangles = nlohmann::json::array();
    for (int i = 0; i < region.face_count(); ++i) {
      const TriangleDistortion& d = quality.texture.per_triangle[i];
      triangles.push_back({{"face", region.faces[i]},
                           {"l2_stretch", d.l2_stretch},
                           {"linf_stretch", d.linf_stretch},
                           {"shear", d.shear},
                           {"flipped", d.flipped},
                           {"degenerate", d.degenerate}});
    }
    j["triangles"] = std::move(triangles);
  }
  if (report.per_vertex) {
    nlohmann::json vertices = nlohmann::json::array();
    for (int i = 0; i < region.vertex_count(); ++i) {
      vertices.push_back(
          {{"vertex", region.vertices[i]},
           {"uv", pixel_to_uv(mapping.texture_px[i], options.texture_width, options.texture_height, report.uv_origin)},
           {"warped_uv", pixel_to_uv(mapping.frame.pixels[i], mapping.frame_width, mapping.frame_height,
                                     report.uv_origin)}});
    }
    j["vertices"] = std::move(vertices);
  }
  return j;
}

}  // namespace texwarp::mesh
