// VelocityField: the time-dependent field v(p, t) of Eq. 2–7 in the closed form of DESIGN.md §1, of one trajectory
// segment on its local time t ∈ [0, 1]: v = (A·p + B) / C with A = Σ w·c, B = Σ w·k, C = Σ w over ordered
// positional pairs and gradient features.
// Exact and finite at and arbitrarily near features (the singular weights are rescaled by the nearest one).
#pragma once

#include <cstddef>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

// Everything of the field that depends on t only (DESIGN.md: compute once per time, share across points).
struct FieldCoefficients {
  double t = 0.0;
  std::vector<Point> positions;        // F_i(t), positional features
  std::vector<Point> velocities;       // D_i
  std::vector<Point> pair_c;           // c_ij = (D_j − D_i)/(F_j − F_i), i < j, row-major packed
  std::vector<Point> pair_k;           // k_ij = D_i − F_i·c_ij (so v_ij(p) = k_ij + c_ij·p)
  std::vector<Point> grad_positions;   // F_g(t)
  std::vector<Point> grad_velocities;  // D_g
  std::vector<Point> grad_c;           // κ_g
  std::vector<Point> grad_k;           // D_g − κ_g·F_g(t)
};

// Spatial derivatives of the field at a point, as complex numbers: dx = ∂vx/∂x + i·∂vy/∂x, dy likewise.
struct FieldGradient {
  Point dx;
  Point dy;
};

class VelocityField {
 public:
  // The field of the problem's segment `segment` (0 for straight trajectories, K = 1).
  explicit VelocityField(const WarpProblem& problem, std::size_t segment = 0);

  const WarpProblem& problem() const { return *problem_; }
  const TrajectorySegment& segment() const { return *segment_; }

  // Fills `out` with the coefficients at time t (O(n²) for n positional features).
  void coefficients(double t, FieldCoefficients& out) const;

  // v(p, t) with coefficients from coefficients(t); O(n²). Pixels per unit time.
  Point evaluate(const FieldCoefficients& coeffs, Point p) const;

  // v(p, t) and its spatial gradient ∇v in closed form (Eq. 2–7 differentiated; see the .cpp), finite at and
  // near features; at a feature it is the limit (for alpha > 1, the field is C¹ there).
  Point evaluate(const FieldCoefficients& coeffs, Point p, FieldGradient& gradient) const;

  // Convenience: both steps for one point.
  Point operator()(Point p, double t) const;

 private:
  template <bool kWithGradient>
  Point evaluate_impl(const FieldCoefficients& c, Point p, FieldGradient* gradient) const;

  const WarpProblem* problem_;
  const TrajectorySegment* segment_;
  double half_alpha_;
  double inv_length2_;  // 1 / weight_length_px²: distances in the weights' unit
};

}  // namespace texwarp
