// Dormand–Prince 5(4) pathline integration with a shared step sequence per batch: see pathline.hpp.
#include "texwarp/core/pathline.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "texwarp/core/dormand_prince.hpp"
#include "texwarp/core/numerical_error.hpp"

namespace texwarp {
namespace {

using dormand_prince::kA;
using dormand_prince::kC;
using dormand_prince::kE;
using dormand_prince::kMaxGrowth;
using dormand_prince::kMaxShrink;
using dormand_prince::kMinStep;
using dormand_prince::kSafety;

// The state of one point: its position and, with the variational equation, the Jacobian's two columns.
template <bool kWithJacobian>
struct State;

template <>
struct State<false> {
  Point p;
};

template <>
struct State<true> {
  Point p;
  Point jx;
  Point jy;
};

template <bool kWithJacobian>
IntegrationStats integrate(const VelocityField& field, std::span<Point> points, std::span<FlowJacobian> jacobians,
                           Direction direction, double tolerance_px) {
  using S = State<kWithJacobian>;
  IntegrationStats stats;
  const std::size_t count = points.size();
  if constexpr (kWithJacobian) {
    for (FlowJacobian& j : jacobians) j = FlowJacobian{};
  }
  if (count == 0 || field.segment().field_is_zero) return stats;

  const double t_start = direction == Direction::kForward ? 0.0 : 1.0;
  const double t_end = 1.0 - t_start;
  const double sign = direction == Direction::kForward ? 1.0 : -1.0;
  const double local_tol = kLocalErrorFraction * tolerance_px;  // per unit time

  std::array<std::vector<S>, 7> k;  // stage derivatives
  for (auto& stage : k) stage.resize(count);
  std::vector<S> y(count);
  std::vector<S> trial(count);
  std::vector<S> stage_point(count);
  for (std::size_t i = 0; i < count; ++i) {
    y[i].p = points[i];
    if constexpr (kWithJacobian) {
      y[i].jx = Point(1.0, 0.0);
      y[i].jy = Point(0.0, 1.0);
    }
  }
  FieldCoefficients coeffs;
  auto derivative = [&](const S& state) {
    S d;
    if constexpr (kWithJacobian) {
      FieldGradient g;
      d.p = field.evaluate(coeffs, state.p, g);
      d.jx = g.dx * state.jx.real() + g.dy * state.jx.imag();  // ∇v applied to each column
      d.jy = g.dx * state.jy.real() + g.dy * state.jy.imag();
    } else {
      d.p = field.evaluate(coeffs, state.p);
    }
    return d;
  };
  auto combine = [](const S& base, double hs, const std::array<std::vector<S>, 7>& kk, const double* coef, int stages,
                    std::size_t i) {
    S out = base;
    Point acc = 0.0;
    for (int j = 0; j < stages; ++j) acc += coef[j] * kk[j][i].p;
    out.p += hs * acc;
    if constexpr (kWithJacobian) {
      Point ax = 0.0;
      Point ay = 0.0;
      for (int j = 0; j < stages; ++j) {
        ax += coef[j] * kk[j][i].jx;
        ay += coef[j] * kk[j][i].jy;
      }
      out.jx += hs * ax;
      out.jy += hs * ay;
    }
    return out;
  };

  double t = t_start;
  double h = dormand_prince::first_step(field.segment().time_scale);  // magnitude
  field.coefficients(t, coeffs);
  for (std::size_t i = 0; i < count; ++i) k[0][i] = derivative(y[i]);
  stats.evaluations = 1;

  const std::vector<NearCollision>& near_collisions = field.segment().near_collisions;
  while (sign * (t_end - t) > 0.0) {
    // Near-collisions: while two trajectories pass close, the field changes within the event's width of its
    // time, and a step longer than that can straddle the change with every stage outside it, so that the error
    // estimate stays small while the step is wrong. A step may end at such a time but not jump over it, and
    // near it stays within the width (as the OpenCL kernel does, kernels/cl/pathline.cl).
    for (const NearCollision& e : near_collisions) h = std::min(h, std::max(e.width, std::abs(e.t - t)));
    bool last = false;
    if (h >= sign * (t_end - t)) {
      h = sign * (t_end - t);
      last = true;
    }
    const double hs = sign * h;
    for (int s = 1; s < 7; ++s) {
      const double ts = (s == 6 && last) ? t_end : t + kC[s] * hs;
      field.coefficients(ts, coeffs);
      std::vector<S>& ys = s == 6 ? trial : stage_point;
      for (std::size_t i = 0; i < count; ++i) ys[i] = combine(y[i], hs, k, kA[s], s, i);
      for (std::size_t i = 0; i < count; ++i) k[s][i] = derivative(ys[i]);
    }
    stats.evaluations += 6;

    double err = 0.0;  // the positions' (and Jacobians') error estimate steers the step
    for (std::size_t i = 0; i < count; ++i) {
      Point e = 0.0;
      for (int j = 0; j < 7; ++j) e += kE[j] * k[j][i].p;
      double ep = h * std::abs(e);
      if constexpr (kWithJacobian) {
        Point ex = 0.0;
        Point ey = 0.0;
        for (int j = 0; j < 7; ++j) {
          ex += kE[j] * k[j][i].jx;
          ey += kE[j] * k[j][i].jy;
        }
        const double ej = h * kJacobianErrorLengthPx * std::max(std::abs(ex), std::abs(ey));
        if (!(ej <= ep)) ep = ej;
      }
      if (!(ep <= err)) err = ep;  // also propagates NaN
    }
    if (!std::isfinite(err)) {
      throw NumericalError("pathline integration produced a non-finite value near t = " + std::to_string(t));
    }
    const double allowed = local_tol * h;
    const double factor =
        err == 0.0 ? kMaxGrowth : std::clamp(kSafety * std::pow(allowed / err, 0.25), kMaxShrink, kMaxGrowth);
    if (err <= allowed) {
      t = last ? t_end : t + hs;
      std::swap(y, trial);
      std::swap(k[0], k[6]);  // FSAL
      ++stats.steps;
      h *= factor;
    } else {
      ++stats.rejected;
      h *= std::min(factor, 1.0);
      if (h < kMinStep) {
        throw NumericalError("pathline step size collapsed near t = " + std::to_string(t) +
                             " (the field is not smooth enough there; are two features nearly colliding?)");
      }
    }
  }
  for (std::size_t i = 0; i < count; ++i) {
    points[i] = y[i].p;
    if constexpr (kWithJacobian) jacobians[i] = FlowJacobian{y[i].jx, y[i].jy};
  }
  return stats;
}

}  // namespace

IntegrationStats integrate_pathlines(const VelocityField& field, std::span<Point> points, Direction direction,
                                     double tolerance_px) {
  return integrate<false>(field, points, {}, direction, tolerance_px);
}

IntegrationStats integrate_pathlines(const VelocityField& field, std::span<Point> points,
                                     std::span<FlowJacobian> jacobians, Direction direction, double tolerance_px) {
  if (jacobians.size() != points.size()) throw std::invalid_argument("integrate_pathlines: one Jacobian per point");
  return integrate<true>(field, points, jacobians, direction, tolerance_px);
}

}  // namespace texwarp
