// Untangling UVs with fixed pins: the regularised barrier energy of Garanzha, Kaporin, Kudryavtseva, Protais, Ray and
// Sokolov, "Foldover-free maps in 50 lines of code" (ACM TOG 40(4) 2021). Each triangle's energy is finite for any
// sign of its Jacobian's determinant D, through χ(D, ε) = (D + √(ε² + D²)) / 2 in place of D; minimised by L-BFGS
// while ε falls each round as the paper's schedule sets it, flipped triangles unfold while the others keep their
// shape. It lets a map whose piecewise-linear UVs flip a few triangles (a fold-free warp sampled at vertices, where
// it bends inside a triangle) become flip-free on the same faces, the pins where they were.
#pragma once

#include <span>

#include "texwarp/core/point.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/mesh/uv_optimization.hpp"

namespace texwarp::mesh {

struct UvUntanglingOptions {
  int max_rounds = 100;           // values of ε (each one L-BFGS minimisation)
  int max_steps_per_round = 200;  // L-BFGS iterations per round
  int patience = 30;              // rounds without fewer refused triangles before it gives up
  // Only the vertices within `rings` edges of a refused triangle move at first (the rest held where they are), then
  // within twice as many, and so on, while refused triangles remain, until every vertex not held by the caller
  // moves; rounds and patience count over all of these. −1: every vertex moves from the start.
  int rings = 8;
  // Weight of the area term (D² + 1)/χ against the shape term ‖J‖²/χ: the paper's λ. Small: the shape (angles) is
  // what the untangled triangles keep; the area term only keeps them from collapsing.
  double area_weight = 1.0 / 128.0;
};

struct UvUntangling {
  int rejected_before = 0;  // triangles `acceptable` refused at the start
  int rejected_after = 0;   // in the UVs handed back (the start's count when nothing better was found)
  int rounds = 0;
  bool applied = false;  // the UVs were replaced (by a result with fewer refused triangles)
};

// Unfolds `uv` (domain positions, v up, per vertex of `mesh`) with the vertices in `fixed` held where they are,
// until every triangle passes `acceptable`, or the count of refused triangles has not fallen for `patience` rounds
// with every vertex free to move (see `rings`), or the rounds run out. A round costs the moving vertices' triangles.
// `uv` is replaced only by a result with fewer refused triangles than the start (the one with fewest). It cannot unfold
// a triangle whose three corners are all held. Triangles of zero surface area count only through `acceptable`.
// CanceledError when `control` is cancelled (between rounds; `uv` then unchanged).
UvUntangling untangle_uvs(const TriangleMesh& mesh, std::span<Point> uv, std::span<const int> fixed,
                          const UvTriangleCheck& acceptable, const UvUntanglingOptions& options = {},
                          const RunControl& control = {});

}  // namespace texwarp::mesh
