// Pathline integration of dp/dt = v(p, t) (Eq. 1) over one trajectory segment (the field's): forward t = 0 → 1
// gives its W_k, inverse t = 1 → 0 gives W_k⁻¹.
// Dormand–Prince 5(4) with error control; a batch of points shares one step sequence so that the
// time-only coefficients of the field are computed once per stage for the whole batch. Steps do not jump over
// the segment's near-collisions (TrajectorySegment::near_collisions).
#pragma once

#include <cstddef>
#include <span>

#include "texwarp/core/direction.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/velocity_field.hpp"

namespace texwarp {

struct IntegrationStats {
  std::size_t steps = 0;        // accepted steps
  std::size_t rejected = 0;     // rejected steps
  std::size_t evaluations = 0;  // field evaluations per point
};

// Local error per unit time allowed to every point, as a fraction of the tolerance: the sum of local errors
// over t ∈ [0, 1] stays a tenth of the tolerance, leaving room for their growth along the flow.
inline constexpr double kLocalErrorFraction = 0.1;

// With the variational equation, the Jacobian's error estimate steers the step too, counted as the position
// error it makes at this distance: a pathline that moves with a feature (its position error estimate is zero)
// still gets its Jacobian to the tolerance.
inline constexpr double kJacobianErrorLengthPx = 1.0;

// The Jacobian of the flow at a point: its columns ∂p(1)/∂x₀ and ∂p(1)/∂y₀ as complex numbers.
struct FlowJacobian {
  Point dx{1.0, 0.0};
  Point dy{0.0, 1.0};

  double det() const { return dx.real() * dy.imag() - dx.imag() * dy.real(); }
};

// Moves every point along its pathline, in place. tolerance_px bounds the error of each point's end position
// (pixels). Throws NumericalError if the step size collapses (it does not for validated problems).
IntegrationStats integrate_pathlines(const VelocityField& field, std::span<Point> points, Direction direction,
                                     double tolerance_px);

// The same, also integrating the variational equation dJ/dt = ∇v·J (J(start) = identity) with each pathline:
// on return jacobians[i] is the Jacobian of the flow (W or W⁻¹) at the i-th starting point. Step control
// follows the positions, as above.
IntegrationStats integrate_pathlines(const VelocityField& field, std::span<Point> points,
                                     std::span<FlowJacobian> jacobians, Direction direction, double tolerance_px);

}  // namespace texwarp
