// Bicubic Hermite cell interpolation: see hermite_cell.hpp.
#include "texwarp/core/hermite_cell.hpp"

namespace texwarp {
namespace {

// Cubic Hermite basis on [0, 1]: value weights for the ends (h00, h01), slope weights (h10, h11).
struct Basis {
  double value[2];
  double slope[2];
  double d_value[2];
  double d_slope[2];
};

inline Basis basis(double t) {
  const double t2 = t * t;
  const double t3 = t2 * t;
  return {{2 * t3 - 3 * t2 + 1, -2 * t3 + 3 * t2},
          {t3 - 2 * t2 + t, t3 - t2},
          {6 * t2 - 6 * t, -6 * t2 + 6 * t},
          {3 * t2 - 4 * t + 1, 3 * t2 - 2 * t}};
}

}  // namespace

HermiteCell::HermiteCell(const Point values[4], const FlowJacobian jacobians[4], const FlowJacobian midpoints[4],
                         double size)
    : size_(size) {
  for (int c = 0; c < 4; ++c) {
    f_[c] = values[c];
    fu_[c] = size * jacobians[c].dx;
    fv_[c] = size * jacobians[c].dy;
  }
  const Point fu_left = size * midpoints[1].dx;  // ∂f/∂u at (0, ½) and (1, ½)
  const Point fu_right = size * midpoints[2].dx;
  const Point fv_bottom = size * midpoints[0].dy;  // ∂f/∂v at (½, 0) and (½, 1)
  const Point fv_top = size * midpoints[3].dy;
  // ∂²f/∂u∂v at each corner: the derivative along v of ∂f/∂u (left or right edge) and along u of ∂f/∂v (bottom
  // or top edge), each by the three-point (quadratic) difference at the end, averaged.
  twist_[0] = 0.5 * ((-3.0 * fu_[0] + 4.0 * fu_left - fu_[2]) + (-3.0 * fv_[0] + 4.0 * fv_bottom - fv_[1]));
  twist_[1] = 0.5 * ((-3.0 * fu_[1] + 4.0 * fu_right - fu_[3]) + (fv_[0] - 4.0 * fv_bottom + 3.0 * fv_[1]));
  twist_[2] = 0.5 * ((fu_[0] - 4.0 * fu_left + 3.0 * fu_[2]) + (-3.0 * fv_[2] + 4.0 * fv_top - fv_[3]));
  twist_[3] = 0.5 * ((fu_[1] - 4.0 * fu_right + 3.0 * fu_[3]) + (fv_[2] - 4.0 * fv_top + 3.0 * fv_[3]));
}

HermiteCell HermiteCell::with_twists(const Point values[4], const FlowJacobian jacobians[4], const Point twists[4],
                                     double size) {
  HermiteCell cell;
  cell.size_ = size;
  for (int c = 0; c < 4; ++c) {
    cell.f_[c] = values[c];
    cell.fu_[c] = size * jacobians[c].dx;
    cell.fv_[c] = size * jacobians[c].dy;
    cell.twist_[c] = twists[c];
  }
  return cell;
}

Point HermiteCell::value(double u, double v) const {
  FlowJacobian unused;
  return value(u, v, unused);
}

Point HermiteCell::value(double u, double v, FlowJacobian& jacobian) const {
  const Basis bu = basis(u);
  const Basis bv = basis(v);
  Point f = 0.0;
  Point fu = 0.0;
  Point fv = 0.0;
  for (int j = 0; j < 2; ++j) {
    for (int i = 0; i < 2; ++i) {
      const int c = 2 * j + i;
      f += bu.value[i] * bv.value[j] * f_[c] + bu.slope[i] * bv.value[j] * fu_[c] + bu.value[i] * bv.slope[j] * fv_[c] +
           bu.slope[i] * bv.slope[j] * twist_[c];
      fu += bu.d_value[i] * bv.value[j] * f_[c] + bu.d_slope[i] * bv.value[j] * fu_[c] +
            bu.d_value[i] * bv.slope[j] * fv_[c] + bu.d_slope[i] * bv.slope[j] * twist_[c];
      fv += bu.value[i] * bv.d_value[j] * f_[c] + bu.slope[i] * bv.d_value[j] * fu_[c] +
            bu.value[i] * bv.d_slope[j] * fv_[c] + bu.slope[i] * bv.d_slope[j] * twist_[c];
    }
  }
  jacobian = FlowJacobian{fu / size_, fv / size_};
  return f;
}

}  // namespace texwarp
