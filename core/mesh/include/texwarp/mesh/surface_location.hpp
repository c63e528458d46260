// Places on a mesh surface: a face with barycentric weights, its 3D position, and the nearest point of a
// region's surface to a 3D point (brute force over the region's faces: O(faces) per query).
#pragma once

#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

struct SurfacePoint {
  int face = -1;  // mesh face id
  Barycentric barycentric{};
};

inline Vec3 surface_position(const TriangleMesh& mesh, const SurfacePoint& p) {
  return interpolate(mesh.corner(p.face, 0), mesh.corner(p.face, 1), mesh.corner(p.face, 2), p.barycentric);
}

struct NearestSurfacePoint {
  SurfacePoint location;
  Vec3 point;
  double distance = 0.0;  // world units
};

NearestSurfacePoint nearest_region_point(const TriangleMesh& mesh, const MeshRegion& region, Vec3 query);

// Diagonal of the region's bounding box (world units).
double region_diagonal(const TriangleMesh& mesh, const MeshRegion& region);

}  // namespace texwarp::mesh
