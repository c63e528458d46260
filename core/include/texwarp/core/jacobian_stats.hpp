// Jacobian determinants of a map at points, and their statistics: minimum, maximum and how many are ≤ 0 (a
// fold). A closed-form map (the baselines) is differentiated by central differences; the warp's Jacobian is
// integrated along each pathline (the variational equation) at a tight tolerance: differences of pathlines,
// each off by up to its tolerance, misjudge the sign where the map squeezes hard (det ~1e-4 next to a
// near-collision).
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

struct JacobianStats {
  double min_det = 0.0;
  double max_det = 0.0;
  std::size_t samples = 0;
  std::size_t nonpositive = 0;  // det ≤ 0, or NaN
};

// Pathline tolerance of the warp's Jacobians, and the difference step for closed-form maps.
inline constexpr double kJacobianTolerancePx = 1e-7;
inline constexpr double kJacobianStepPx = 1e-3;

JacobianStats summarize_determinants(const std::vector<double>& determinants);

// det ∂map/∂p at every point by central differences with step h. `map` transforms points in place; it is
// called once with the four neighbours of every point, consecutive.
std::vector<double> jacobian_determinants(const std::function<void(std::vector<Point>&)>& map,
                                          const std::vector<Point>& points, double h);

// warp_jacobians runs its points in up to kJacobianParts backend calls (progress and cancellation between them),
// each of blocks of kJacobianBlockPoints points consecutive in Morton order taken round-robin, at least
// kJacobianMinBlocksPerPart blocks a call: one call of a 128² grid at 1e-7 px ran 15 s on OpenCL without a step.
inline constexpr std::size_t kJacobianParts = 16;
inline constexpr std::size_t kJacobianBlockPoints = 256;
inline constexpr std::size_t kJacobianMinBlocksPerPart = 4;

// The Jacobian of f (kForward) or f⁻¹ (kInverse) at every point: the variational equation on a copy of the
// problem integrated at kJacobianTolerancePx.
std::vector<FlowJacobian> warp_jacobians(WarpBackend& backend, const WarpProblem& problem,
                                         const std::vector<Point>& points, Direction direction,
                                         const RunControl& control = {});

// σ1/σ2, the ratio of a Jacobian's singular values: 1 for a conformal map, +inf where it is singular.
double singular_value_ratio(const FlowJacobian& j);

// σ1, a Jacobian's largest singular value: how far it stretches a vector at most.
double largest_singular_value(const FlowJacobian& j);

// det of f (kForward) or f⁻¹ (kInverse) at every point: the determinants of warp_jacobians.
std::vector<double> warp_jacobian_determinants(WarpBackend& backend, const WarpProblem& problem,
                                               const std::vector<Point>& points, Direction direction,
                                               const RunControl& control = {});

}  // namespace texwarp
