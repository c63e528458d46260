// The Jacobian of a UV map on each triangle of a surface, measured in the triangle's own 2D frame, the surface
// scaled so that its area equals the UVs' (an isometry then has singular values 1): what the UV optimisation
// (uv_optimization.hpp) and the untangling (uv_untangling.hpp) measure distortion with.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

// A triangle of the surface in a 2D frame of its own: the gradients of its three barycentric functions (scaled
// surface units) and its scaled area; all zero for a triangle of zero surface area. J = [∇u; ∇v] = Σ_k (u_k, v_k) ⊗
// g_k.
struct SurfaceTriangle {
  std::array<double, 3> gx{}, gy{};
  double area = 0.0;
};

struct Jacobian {
  double a = 0, b = 0, c = 0, d = 0;  // [[∂u/∂x, ∂u/∂y], [∂v/∂x, ∂v/∂y]]
  double det() const { return a * d - b * c; }
};

// Every face of `mesh`, the surface scaled by √(Σ|UV area| / surface area) of `uv` (1 when either is zero).
std::vector<SurfaceTriangle> surface_triangles(const TriangleMesh& mesh, std::span<const Point> uv);

inline Jacobian jacobian(const SurfaceTriangle& t, const Face& f, std::span<const Point> uv) {
  Jacobian j;
  for (int k = 0; k < 3; ++k) {
    const Point p = uv[f[k]];
    j.a += p.real() * t.gx[k];
    j.b += p.real() * t.gy[k];
    j.c += p.imag() * t.gx[k];
    j.d += p.imag() * t.gy[k];
  }
  return j;
}

}  // namespace texwarp::mesh
