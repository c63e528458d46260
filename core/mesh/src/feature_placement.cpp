// Surface features into the texture frame: see feature_placement.hpp.
#include "texwarp/mesh/feature_placement.hpp"

#include <cmath>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::mesh {
namespace {

// A tangent direction closer than this (sine of the angle) to the face normal is refused.
constexpr double kMinTangentSine = 1e-3;

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

Point frame_position(const MeshRegion& region, std::span<const Point> frame_px, const TriangleMesh& mesh,
                     const SurfacePoint& p) {
  const Face& f = mesh.faces[p.face];
  Point q(0.0, 0.0);
  for (int k = 0; k < 3; ++k) q += p.barycentric[k] * frame_px[region.local_vertex[f[k]]];
  return q;
}

}  // namespace

Point map_tangent(Vec3 p0, Vec3 p1, Vec3 p2, Point q0, Point q1, Point q2, Vec3 d) {
  // d ≈ α·e1 + β·e2 in the least-squares sense (its normal component drops out), then J·d = α·f1 + β·f2.
  const Vec3 e1 = p1 - p0;
  const Vec3 e2 = p2 - p0;
  const double g11 = dot(e1, e1), g12 = dot(e1, e2), g22 = dot(e2, e2);
  const double r1 = dot(e1, d), r2 = dot(e2, d);
  const double det = g11 * g22 - g12 * g12;
  const double alpha = (g22 * r1 - g12 * r2) / det;
  const double beta = (g11 * r2 - g12 * r1) / det;
  return alpha * (q1 - q0) + beta * (q2 - q0);
}

Frame gradient_target_frame(const TriangleMesh& mesh, const MeshRegion& region, std::span<const Point> frame_px,
                            int face, const SurfaceFrame& target, const Frame& source, const JsonPath& where) {
  const Face& f = mesh.faces[face];
  const Vec3 p0 = mesh.vertices[f[0]], p1 = mesh.vertices[f[1]], p2 = mesh.vertices[f[2]];
  const Vec3 n = doubled_normal(p0, p1, p2);
  const Vec3 d = target.direction / norm(target.direction);
  const Vec3 tangent = d - (dot(d, n) / dot(n, n)) * n;
  const double sine = norm(tangent);
  if (sine < kMinTangentSine) {
    throw InputError(where, "the direction is (nearly) normal to the surface at the feature (face " +
                                std::to_string(face) + "): give a direction along the surface");
  }
  const Vec3 unit = tangent / sine;
  const Point j = map_tangent(p0, p1, p2, frame_px[region.local_vertex[f[0]]], frame_px[region.local_vertex[f[1]]],
                              frame_px[region.local_vertex[f[2]]], unit);
  Frame out;
  out.angle_rad = std::arg(j);
  out.scale = source.scale * std::abs(j) / target.texels_per_unit;
  return out;
}

std::vector<PlacedFeature> place_surface_features(const TriangleMesh& mesh, const MeshRegion& region,
                                                  std::span<const Point> frame_px, const SurfaceFeatureSet& set,
                                                  const JsonPath& path) {
  const double snap = set.snap_tolerance ? *set.snap_tolerance : kDefaultSnapFraction * region_diagonal(mesh, region);
  const JsonPath features_path = path.key("features");
  std::vector<PlacedFeature> placed;
  placed.reserve(set.features.size());
  for (std::size_t i = 0; i < set.features.size(); ++i) {
    const SurfaceFeature& sf = set.features[i];
    const JsonPath fpath = features_path.index(i);
    const JsonPath tpath = fpath.key("target");
    PlacedFeature p;
    if (const auto* ft = std::get_if<FaceTarget>(&sf.target)) {
      const JsonPath where = tpath.key("face");
      if (ft->face >= mesh.face_count()) {
        throw InputError(where, "face " + std::to_string(ft->face) + " does not exist (the mesh has " +
                                    std::to_string(mesh.face_count()) + " faces)");
      }
      if (region.local_face[ft->face] < 0) {
        throw InputError(where, "face " + std::to_string(ft->face) + " is not in the region");
      }
      p.location = {ft->face, ft->barycentric};
    } else if (const auto* vt = std::get_if<VertexTarget>(&sf.target)) {
      const JsonPath where = tpath.key("vertex");
      if (vt->vertex >= mesh.vertex_count()) {
        throw InputError(where, "vertex " + std::to_string(vt->vertex) + " does not exist (the mesh has " +
                                    std::to_string(mesh.vertex_count()) + " vertices)");
      }
      if (region.local_vertex[vt->vertex] < 0) {
        throw InputError(where, "vertex " + std::to_string(vt->vertex) + " is not in the region");
      }
      for (int f : region.faces) {  // the first region face around the vertex
        const Face& face = mesh.faces[f];
        const int v = vt->vertex;
        const int k = face[0] == v ? 0 : (face[1] == v ? 1 : (face[2] == v ? 2 : -1));
        if (k >= 0) {
          p.location.face = f;
          p.location.barycentric = {0.0, 0.0, 0.0};
          p.location.barycentric[k] = 1.0;
          break;
        }
      }
    } else {
      const Vec3 q = std::get<PointTarget>(sf.target).point;
      const NearestSurfacePoint n = nearest_region_point(mesh, region, q);
      if (n.distance > snap) {
        throw InputError(tpath.key("point"),
                         "the point is " + number(n.distance) + " from the region's surface (nearest: face " +
                             std::to_string(n.location.face) + "), farther than the snap tolerance " + number(snap));
      }
      p.location = n.location;
      p.snap_distance = n.distance;
    }
    p.position = surface_position(mesh, p.location);
    p.feature.id = sf.id;
    p.feature.source = sf.source;
    p.feature.target = frame_position(region, frame_px, mesh, p.location);
    if (sf.is_gradient()) {
      p.feature.source_frame = *sf.source_frame;
      p.feature.target_frame = gradient_target_frame(mesh, region, frame_px, p.location.face, *sf.target_frame,
                                                     *sf.source_frame, fpath.key("target_frame"));
    }
    placed.push_back(std::move(p));
  }
  return placed;
}

}  // namespace texwarp::mesh
