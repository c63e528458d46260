// Free-boundary least squares conformal map (Lévy, Petitjean, Ray, Maillot, SIGGRAPH 2002) of a disk-shaped
// mesh: two vertices pinned far apart, every other vertex free, the conformal energy minimised in the
// least-squares sense (Eigen sparse Cholesky on the normal equations).
#pragma once

#include <array>
#include <optional>
#include <span>

#include "texwarp/core/point.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

struct LscmEmbedding {
  std::vector<Point> positions;  // per vertex, x + i·y with y up; the faces keep their orientation (CCW)
  std::array<int, 2> pinned{};   // the two pinned vertices: at 0 and at |p1 − p0| (world units) on the x axis
  double energy = 0.0;           // conformal energy of `positions` (lscm_energy)
};

// Conformal energy of a planar map of the mesh (Lévy et al. 2002): E = Σ_T A_T ((u_x − v_y)² + (u_y + v_x)²), the
// Cauchy–Riemann residuals of the map on each triangle in its own orthonormal frame, A_T its 3D area.
// E = 2·(Dirichlet energy − signed area of the image); 0 exactly for a similarity of a flat mesh.
double lscm_energy(const TriangleMesh& mesh, std::span<const Point> positions);

// The two vertices to pin: boundary vertices far apart (the farthest from the first boundary vertex, then
// the farthest from that one, in 3D). `boundary` may be empty (then all vertices are candidates).
std::array<int, 2> lscm_pin_vertices(const TriangleMesh& mesh, std::span<const int> boundary);

// The embedding of a connected, validated mesh (a disk for a bijective result). `pinned` overrides the
// choice of lscm_pin_vertices. NumericalError if the solve fails.
LscmEmbedding lscm_embedding(const TriangleMesh& mesh, std::span<const int> boundary,
                             std::optional<std::array<int, 2>> pinned = std::nullopt);

}  // namespace texwarp::mesh
