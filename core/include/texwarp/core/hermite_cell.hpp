// HermiteCell: bicubic Hermite interpolation of a planar map over a square cell from the map's values and
// Jacobians at the four corners (twist estimated from the corner Jacobians), with the interpolant's Jacobian.
#pragma once

#include "texwarp/core/pathline.hpp"
#include "texwarp/core/point.hpp"

namespace texwarp {

class HermiteCell {
 public:
  // Corners in the order (x0, y0), (x0 + size, y0), (x0, y0 + size), (x0 + size, y0 + size).
  HermiteCell(const Point values[4], const FlowJacobian jacobians[4], double size);

  // The interpolant at local offsets (u, v) ∈ [0, 1]² (u along x), and its Jacobian in pixel units.
  Point value(double u, double v) const;
  Point value(double u, double v, FlowJacobian& jacobian) const;

 private:
  Point f_[4];
  Point fu_[4];  // ∂f/∂u = size·∂f/∂x
  Point fv_[4];
  Point twist_;  // ∂²f/∂u∂v, one for the cell
  double size_;
};

}  // namespace texwarp
