// Nearest region point and region size: see surface_location.hpp.
#include "texwarp/mesh/surface_location.hpp"

#include <algorithm>
#include <limits>

namespace texwarp::mesh {

NearestSurfacePoint nearest_region_point(const TriangleMesh& mesh, const MeshRegion& region, Vec3 query) {
  NearestSurfacePoint best;
  best.distance = std::numeric_limits<double>::infinity();
  for (int f : region.faces) {
    const ClosestPoint c = closest_point_on_triangle(query, mesh.corner(f, 0), mesh.corner(f, 1), mesh.corner(f, 2));
    if (c.distance < best.distance) {
      best.location = {f, c.barycentric};
      best.point = c.point;
      best.distance = c.distance;
    }
  }
  return best;
}

double region_diagonal(const TriangleMesh& mesh, const MeshRegion& region) {
  Vec3 lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
          std::numeric_limits<double>::infinity()};
  Vec3 hi = -1.0 * lo;
  for (int v : region.vertices) {
    const Vec3 p = mesh.vertices[v];
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  return norm(hi - lo);
}

}  // namespace texwarp::mesh
