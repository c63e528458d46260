// Injectivity-preserving optimisation of UVs with fixed pins: scalable locally injective mappings (SLIM, Rabinovich,
// Lipman, Sorkine-Hornung, ACM TOG 36(2) 2017) on the symmetric Dirichlet energy, from a start without flips, with a
// line search that never lets a triangle reach det = 0 (Smith & Schaefer, "Bijective parameterization with free
// boundaries", SIGGRAPH 2015) nor leave what `acceptable` allows.
#pragma once

#include <functional>
#include <span>

#include "texwarp/core/point.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

struct UvOptimizationOptions {
  int max_iterations = 30;
  double relative_decrease = 1e-3;  // stop when an iteration lowers the energy by less than this fraction
};

struct UvOptimization {
  // Mean symmetric Dirichlet energy per unit surface area, Σ A (‖J‖² + ‖J⁻¹‖²) / Σ A with J the map from the
  // surface (scaled so that its area equals the UVs') to the UVs: 4 for an isometry.
  double energy_before = 0.0;
  double energy_after = 0.0;
  int iterations = 0;
  bool converged = false;  // the last iteration's decrease was below `relative_decrease`
};

// Whether a UV triangle (domain positions, v up, counter-clockwise = front) may be handed out.
using UvTriangleCheck = std::function<bool(Point, Point, Point)>;

// Lowers the symmetric Dirichlet energy of `uv` (domain positions, v up, per vertex of `mesh`) with the vertices in
// `fixed` held where they are. Every triangle of `uv` must pass `acceptable` on entry (NumericalError otherwise) and
// passes it at every accepted step, so the result is as injective as the start. Triangles of zero surface area count
// only through `acceptable`.
UvOptimization optimize_uvs(const TriangleMesh& mesh, std::span<Point> uv, std::span<const int> fixed,
                            const UvTriangleCheck& acceptable, const UvOptimizationOptions& options = {});

}  // namespace texwarp::mesh
