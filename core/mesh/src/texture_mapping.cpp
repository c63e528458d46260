// The texture-mapping pipeline: see texture_mapping.hpp.
#include "texwarp/mesh/texture_mapping.hpp"

#include <chrono>

#include "texwarp/mesh/embedding_repair.hpp"

#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::vector<Point> pixels_to_domain(std::span<const Point> pixels) {
  std::vector<Point> out(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) out[i] = Point(pixels[i].real(), -pixels[i].imag());
  return out;
}

TextureMapping map_texture(WarpBackend& backend, const TriangleMesh& mesh, MeshRegion region,
                           const SurfaceFeatureSet& features, const TextureMappingOptions& options,
                           const RunControl& control, const JsonPath& features_path) {
  if (options.texture_width <= 0 || options.texture_height <= 0) {
    throw InputError({}, "the texture must have a positive size, got " + std::to_string(options.texture_width) + "×" +
                             std::to_string(options.texture_height));
  }
  TextureMapping out;
  out.region = std::move(region);
  out.frame_width = options.frame_width > 0 ? options.frame_width : options.texture_width;
  out.frame_height = options.frame_height > 0 ? options.frame_height : options.texture_height;

  auto start = std::chrono::steady_clock::now();
  out.lscm = lscm_embedding(out.region.local, out.region.boundary);
  EmbeddingRepair repair = repair_embedding(out.region.local, out.region.boundary, std::move(out.lscm.positions));
  out.lscm.positions = std::move(repair.positions);
  out.embedding = repair.method;
  for (int f : repair.flipped_faces) out.lscm_flipped_faces.push_back(out.region.faces[f]);
  if (out.embedding != proto::EmbeddingMethod::kLscm)
    out.lscm.energy = lscm_energy(out.region.local, out.lscm.positions);
  out.lscm_seconds = seconds_since(start);

  FramePlacementOptions placement;
  placement.width = out.frame_width;
  placement.height = out.frame_height;
  placement.margin_px = options.margin_px;
  placement.rotate_to_fit = options.rotate_to_fit;
  out.frame = place_in_frame(out.lscm.positions, placement);

  out.features = place_surface_features(mesh, out.region, out.frame.pixels, features, features_path);
  std::vector<Feature> warp_features;
  warp_features.reserve(out.features.size());
  for (const PlacedFeature& p : out.features) warp_features.push_back(p.feature);
  out.problem.emplace(std::move(warp_features), features.options);

  start = std::chrono::steady_clock::now();
  out.texture_px = out.frame.pixels;
  map_points(backend, *out.problem, out.texture_px, Direction::kInverse, control);
  if (options.refine) {
    const RegionVertexData data{out.frame.pixels, out.lscm.positions, out.texture_px};
    out.refinement = refine_region(mesh, out.region, data, out.features, [&](std::span<Point> points) {
      map_points(backend, *out.problem, points, Direction::kInverse, control);
    });
  }
  out.warp_seconds = seconds_since(start);
  return out;
}

MappingQuality evaluate_mapping(const TriangleMesh& mesh, const TextureMapping& mapping,
                                std::span<const Point> texture_px, const TextureMappingOptions& options,
                                bool per_triangle) {
  MappingQuality q;
  q.texture = uv_metrics(mapping.region.local, pixels_to_domain(texture_px), true);
  q.frame = uv_metrics(mapping.region.local, pixels_to_domain(mapping.frame.pixels), true);
  for (int f = 0; f < mapping.region.face_count(); ++f) {
    if (!q.texture.per_triangle[f].flipped) continue;
    const bool embedding = q.frame.per_triangle[f].flipped || q.frame.per_triangle[f].degenerate;
    q.flips.push_back({mapping.region.faces[f], embedding ? proto::FlipCause::kEmbedding : proto::FlipCause::kWarp});
  }
  if (!per_triangle) {
    q.texture.per_triangle.clear();
    q.frame.per_triangle.clear();
  }
  const TriangleMesh& out_mesh = output_mesh(mesh, mapping.refinement);
  double sum = 0.0;
  for (std::size_t i = 0; i < mapping.features.size(); ++i) {
    const PlacedFeature& p = mapping.features[i];
    const SurfacePoint& s = mapping.refinement ? mapping.refinement->feature_locations[i] : p.location;
    const Face& f = out_mesh.faces[s.face];
    Point at(0.0, 0.0);
    for (int k = 0; k < 3; ++k) at += s.barycentric[k] * texture_px[mapping.region.local_vertex[f[k]]];
    const double r = std::abs(at - p.feature.source);
    q.residual_px.push_back(r);
    q.max_residual_px = std::max(q.max_residual_px, r);
    sum += r;
  }
  if (!q.residual_px.empty()) q.mean_residual_px = sum / static_cast<double>(q.residual_px.size());
  for (Point p : texture_px) {
    if (p.real() < 0.0 || p.imag() < 0.0 || p.real() > options.texture_width || p.imag() > options.texture_height) {
      ++q.vertices_outside_texture;
    }
  }
  return q;
}

}  // namespace texwarp::mesh
