// The closed form of a trivial warp: when the field is zero (no features, or every feature exactly where the
// pre-alignment S puts it), f = S and f⁻¹ = S⁻¹ at every pixel: no pathline, no lattice, no compute device.
#pragma once

#include <vector>

#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

// Whether the warp of `problem` is its pre-alignment alone (WarpProblem::field_is_zero()).
inline bool has_closed_form(const WarpProblem& problem) { return problem.field_is_zero(); }

// S⁻¹ at every output pixel centre (x + 0.5, y + 0.5), row-major, width·height entries. Requires has_closed_form.
std::vector<Point> closed_form_inverse_map_grid(const WarpProblem& problem, int width, int height);

// The certificate of the closed form: exact, zero error, no pathlines; det of the inverse map 1 / |a|² everywhere
// (a: S's rotation·scale). `tolerance_px` is what the warp was asked to meet.
WarpCertificate closed_form_certificate(const WarpProblem& problem, double tolerance_px);

}  // namespace texwarp
