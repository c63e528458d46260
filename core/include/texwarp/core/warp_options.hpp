// WarpOptions: the parameters of the method (DESIGN.md §1) that are not features.
#pragma once

#include "texwarp/proto/warp_spec.hpp"

namespace texwarp {

using proto::Prealign;  // names: proto/warp_spec.hpp

struct WarpOptions {
  double alpha = 2.0;                         // weight exponent of Eq. 5–6; C¹ needs alpha > 1
  Prealign prealign = Prealign::kSimilarity;  // Section 3.3 least-squares similarity first
  double tolerance_px = 0.01;                 // pathline integration error bound, pixels
  double min_separation_px = 0.5;             // closer than this at the same time counts as a collision
  // The planner lowers the pair energy of planned trajectories (trajectory_planner.hpp); with widen_near_misses, also
  // that of straight ones whose pairs pass closer than a quarter of the features' spacing: mesh mappings, where a
  // narrow pass turns triangles over (an image's lattice resolves it, and one straight segment integrates faster).
  bool lower_energy = true;
  bool widen_near_misses = false;
};

// Valid ranges, checked by WarpProblem.
inline constexpr double kMaxAlpha = 8.0;
inline constexpr double kMinTolerancePx = 1e-10;
// The smallest tolerance a backend integrates in float32: below it float32 rounding of positions and weights is no
// longer small against the tolerance, and a float backend (OpenCL's float kernel) switches to double.
inline constexpr double kFloatMinTolerancePx = 1e-3;

}  // namespace texwarp
