// HermiteCell: bicubic Hermite interpolation of a planar map over a square cell from the map's values and
// Jacobians at the four corners, the twist ∂²f/∂x∂y at each corner estimated from the Jacobians at the corners
// and the edge midpoints (second-order differences) or given, with the interpolant's Jacobian.
#pragma once

#include "texwarp/core/pathline.hpp"
#include "texwarp/core/point.hpp"

namespace texwarp {

class HermiteCell {
 public:
  // Corners in the order (x0, y0), (x0 + size, y0), (x0, y0 + size), (x0 + size, y0 + size); edge midpoints'
  // Jacobians in the order bottom (y0), left (x0), right (x0 + size), top (y0 + size). A cubic map (per
  // variable) is reproduced exactly.
  HermiteCell(const Point values[4], const FlowJacobian jacobians[4], const FlowJacobian midpoints[4], double size);
  // The same with the twists ∂²f/∂u∂v (u, v ∈ [0, 1] across the cell) at the corners given.
  static HermiteCell with_twists(const Point values[4], const FlowJacobian jacobians[4], const Point twists[4],
                                 double size);

  // The interpolant at local offsets (u, v) ∈ [0, 1]² (u along x), and its Jacobian in pixel units.
  Point value(double u, double v) const;
  Point value(double u, double v, FlowJacobian& jacobian) const;

 private:
  HermiteCell() = default;
  Point f_[4];
  Point fu_[4];  // ∂f/∂u = size·∂f/∂x
  Point fv_[4];
  Point twist_[4];  // ∂²f/∂u∂v at each corner
  double size_ = 1.0;
};

}  // namespace texwarp
