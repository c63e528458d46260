// Per-triangle frames of a surface for UV Jacobians: see surface_jacobian.hpp.
#include "texwarp/mesh/surface_jacobian.hpp"

#include <cmath>

#include "texwarp/mesh/uv_orientation.hpp"

namespace texwarp::mesh {

std::vector<SurfaceTriangle> surface_triangles(const TriangleMesh& mesh, std::span<const Point> uv) {
  double surface = 0.0, flat = 0.0;
  for (const Face& f : mesh.faces) {
    surface += 0.5 * norm(cross(mesh.vertices[f[1]] - mesh.vertices[f[0]], mesh.vertices[f[2]] - mesh.vertices[f[0]]));
    flat += 0.5 * std::abs(uv_doubled_area(uv[f[0]], uv[f[1]], uv[f[2]]));
  }
  const double scale = surface > 0.0 && flat > 0.0 ? std::sqrt(flat / surface) : 1.0;
  std::vector<SurfaceTriangle> out;
  out.reserve(mesh.faces.size());
  for (const Face& f : mesh.faces) {
    const Vec3 e1 = mesh.vertices[f[1]] - mesh.vertices[f[0]];
    const Vec3 e2 = mesh.vertices[f[2]] - mesh.vertices[f[0]];
    const Vec3 n3 = cross(e1, e2);
    const double doubled = norm(n3) * scale * scale;
    SurfaceTriangle t;
    if (doubled > 0.0 && norm(e1) > 0.0) {
      const Vec3 x = (1.0 / norm(e1)) * e1;
      const Vec3 y = (1.0 / (norm(n3) * norm(e1))) * cross(n3, e1);
      const std::array<Point, 3> p = {Point(0.0, 0.0), Point(scale * norm(e1), 0.0),
                                      Point(scale * dot(e2, x), scale * dot(e2, y))};
      for (int k = 0; k < 3; ++k) {
        const Point edge = p[(k + 2) % 3] - p[(k + 1) % 3];  // ∇λ_k = perp(p_{k+2} − p_{k+1}) / 2A
        t.gx[k] = -edge.imag() / doubled;
        t.gy[k] = edge.real() / doubled;
      }
      t.area = 0.5 * doubled;
    }
    out.push_back(t);
  }
  return out;
}

}  // namespace texwarp::mesh
