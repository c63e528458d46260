// The vector field of Eq. 2–7: see velocity_field.hpp.
//
// Distances enter the weights in units of WarpProblem::weight_length_px (resolution independence).
// Singular weights: with k the feature nearest to p and s = d_k^α, every weight is multiplied by s, which
// leaves the normalised field unchanged: a pair (k, j) weighs a_j, a pair without k weighs a_i·a_j·s, a
// gradient feature g ≠ k weighs b_g·s and k itself (if gradient) weighs 1. All terms stay finite as d_k → 0,
// and at d_k = 0 the field is exactly the feature's velocity D_k (the limit of Section 2.3.3).
#include "texwarp/core/velocity_field.hpp"

#include <cmath>
#include <limits>

namespace texwarp {
namespace {

// Index of the unordered pair (i, j), i < j, among n features packed row-major.
inline std::size_t pair_index(std::size_t i, std::size_t j, std::size_t n) {
  return i * n - i * (i + 1) / 2 + (j - i - 1);
}

}  // namespace

VelocityField::VelocityField(const WarpProblem& problem, std::size_t segment)
    : problem_(&problem),
      segment_(&problem.segments().at(segment)),
      half_alpha_(0.5 * problem.alpha()),
      inv_length2_(1.0 / (segment_->weight_length_px * segment_->weight_length_px)) {}

void VelocityField::coefficients(double t, FieldCoefficients& out) const {
  const auto& pos = segment_->positional;
  const auto& grad = segment_->gradient;
  const std::size_t n = pos.size();
  out.t = t;
  out.positions.resize(n);
  out.velocities.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.positions[i] = pos[i].start + t * pos[i].velocity;
    out.velocities[i] = pos[i].velocity;
  }
  const std::size_t pairs = n < 2 ? 0 : n * (n - 1) / 2;
  out.pair_c.resize(pairs);
  out.pair_k.resize(pairs);
  std::size_t idx = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j, ++idx) {
      // Eq. 2–3 in complex form: the similarity velocity that moves F_i and F_j with their velocities.
      const Point c = (out.velocities[j] - out.velocities[i]) / (out.positions[j] - out.positions[i]);
      out.pair_c[idx] = c;
      out.pair_k[idx] = out.velocities[i] - out.positions[i] * c;
    }
  }
  const std::size_t m = grad.size();
  out.grad_positions.resize(m);
  out.grad_velocities.resize(m);
  out.grad_c.resize(m);
  out.grad_k.resize(m);
  for (std::size_t g = 0; g < m; ++g) {
    const Point f = grad[g].start + t * grad[g].velocity;
    out.grad_positions[g] = f;
    out.grad_velocities[g] = grad[g].velocity;
    out.grad_c[g] = grad[g].rate;
    out.grad_k[g] = grad[g].velocity - grad[g].rate * f;  // Eq. 4: v_g(p) = D_g + κ_g·(p − F_g)
  }
}

// The gradient: with v = Σ W_t·u_t / Σ W_t, u_t(p) = c_t·p + k_t and W_t the (rescaled) weights,
//   ∂v/∂x = (Σ W_t c_t + Σ W_t·G_t.x·(u_t − v)) / Σ W_t,   ∂v/∂y = (i·Σ W_t c_t + Σ W_t·G_t.y·(u_t − v)) / Σ W_t,
// with G_t = ∇ln W_t = Σ over the term's features of g_i = −α (p − F_i)/|p − F_i|². Any common shift of all G_t
// cancels (Σ W_t (u_t − v) = 0), so G_t − g_k is used instead: finite near the nearest feature k, where
// the terms carrying k keep only their partner's g_j and every other term is scaled by s = d_k^α.
template <bool kWithGradient>
Point VelocityField::evaluate_impl(const FieldCoefficients& c, Point p, FieldGradient* gradient) const {
  const std::size_t n = c.positions.size();
  const std::size_t m = c.grad_positions.size();
  if (n == 0 && m == 0) {
    if constexpr (kWithGradient) *gradient = {0.0, 0.0};
    return 0.0;
  }

  thread_local std::vector<double> a;  // positional weights a_i = d_i^−α (a_k = 0 when k is positional)
  thread_local std::vector<double> b;  // gradient weights b_g = d_g^−α
  thread_local std::vector<Point> ga;  // ∇ln a_i (gradient only)
  thread_local std::vector<Point> gb;  // ∇ln b_g
  a.resize(n);
  b.resize(m);

  // Squared distances (in the weights' unit) and the nearest feature.
  double r_min = std::numeric_limits<double>::infinity();
  std::size_t k = 0;
  bool k_positional = true;
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = std::norm(p - c.positions[i]) * inv_length2_;
    if (a[i] < r_min) {
      r_min = a[i];
      k = i;
      k_positional = true;
    }
  }
  for (std::size_t g = 0; g < m; ++g) {
    b[g] = std::norm(p - c.grad_positions[g]) * inv_length2_;
    if (b[g] < r_min) {
      r_min = b[g];
      k = g;
      k_positional = false;
    }
  }
  const Point d_k = k_positional ? c.velocities[k] : c.grad_velocities[k];
  if constexpr (!kWithGradient) {
    if (r_min == 0.0) return d_k;
  }
  const double alpha = 2.0 * half_alpha_;
  if constexpr (kWithGradient) {
    // g_i = −α (p − F_i)/|p − F_i|² in pixels (the length unit cancels in ∇ln).
    ga.resize(n);
    gb.resize(m);
    for (std::size_t i = 0; i < n; ++i) {
      const Point d = p - c.positions[i];
      ga[i] = a[i] > 0.0 ? -alpha * d / std::norm(d) : Point(0.0);
    }
    for (std::size_t g = 0; g < m; ++g) {
      const Point d = p - c.grad_positions[g];
      gb[g] = b[g] > 0.0 ? -alpha * d / std::norm(d) : Point(0.0);
    }
  }

  // d^−α from the squared distance r: r^(−α/2).
  const double h = half_alpha_;
  auto inv_pow = [h](double r) {
    if (h == 1.0) return 1.0 / r;
    if (h == 1.5) return 1.0 / (r * std::sqrt(r));
    if (h == 0.5) return 1.0 / std::sqrt(r);
    if (h == 2.0) return 1.0 / (r * r);
    return std::pow(r, -h);
  };
  const double s = r_min == 0.0 ? 0.0 : 1.0 / inv_pow(r_min);  // d_k^α
  for (std::size_t i = 0; i < n; ++i) a[i] = a[i] > 0.0 ? inv_pow(a[i]) : 0.0;
  for (std::size_t g = 0; g < m; ++g) b[g] = b[g] > 0.0 ? inv_pow(b[g]) : 0.0;
  if (k_positional) a[k] = 0.0;  // pairs with k are added below with their own weights

  // Ordered pairs i ≠ j: twice the unordered sum. Pairs without k, scaled by s.
  Point sum_c = 0.0;
  Point sum_k = 0.0;
  double sum_w = 0.0;
  std::size_t idx = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Point row_c = 0.0;
    Point row_k = 0.0;
    double row_w = 0.0;
    for (std::size_t j = i + 1; j < n; ++j, ++idx) {
      const double w = a[j];
      row_c += w * c.pair_c[idx];
      row_k += w * c.pair_k[idx];
      row_w += w;
    }
    sum_c += a[i] * row_c;
    sum_k += a[i] * row_k;
    sum_w += a[i] * row_w;
  }
  Point A = 2.0 * s * sum_c;
  Point B = 2.0 * s * sum_k;
  double C = 2.0 * s * sum_w;
  if (k_positional) {
    for (std::size_t j = 0; j < n; ++j) {
      if (j == k) continue;
      const std::size_t pj = j < k ? pair_index(j, k, n) : pair_index(k, j, n);
      A += 2.0 * a[j] * c.pair_c[pj];
      B += 2.0 * a[j] * c.pair_k[pj];  // k_jk = k_kj: v_ij = v_ji
      C += 2.0 * a[j];
    }
  }
  for (std::size_t g = 0; g < m; ++g) {
    const double w = (!k_positional && g == k) ? 1.0 : s * b[g];
    A += w * c.grad_c[g];
    B += w * c.grad_k[g];
    C += w;
  }
  const Point v = r_min == 0.0 ? d_k : (A * p + B) / C;
  if constexpr (!kWithGradient) {
    return v;
  } else {
    const Point g_k = k_positional ? ga[k] : gb[k];
    Point sx = 0.0;  // Σ W_t·(G_t − g_k).x·(u_t − v)
    Point sy = 0.0;
    std::size_t q = 0;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = i + 1; j < n; ++j, ++q) {
        const double w = 2.0 * s * a[i] * a[j];  // zero for the pairs with k (a_k = 0 here)
        if (w == 0.0) continue;
        const Point shift = ga[i] + ga[j] - g_k;
        const Point du = c.pair_c[q] * p + c.pair_k[q] - v;
        sx += (w * shift.real()) * du;
        sy += (w * shift.imag()) * du;
      }
    }
    if (k_positional) {
      for (std::size_t j = 0; j < n; ++j) {
        if (j == k) continue;
        const std::size_t pj = j < k ? pair_index(j, k, n) : pair_index(k, j, n);
        const double w = 2.0 * a[j];
        const Point du = c.pair_c[pj] * p + c.pair_k[pj] - v;
        sx += (w * ga[j].real()) * du;
        sy += (w * ga[j].imag()) * du;
      }
    }
    for (std::size_t g = 0; g < m; ++g) {
      if (!k_positional && g == k) continue;  // its shift G − g_k is zero
      const double w = s * b[g];
      const Point shift = gb[g] - g_k;
      const Point du = c.grad_c[g] * p + c.grad_k[g] - v;
      sx += (w * shift.real()) * du;
      sy += (w * shift.imag()) * du;
    }
    gradient->dx = (A + sx) / C;
    gradient->dy = (Point(0.0, 1.0) * A + sy) / C;
    return v;
  }
}

Point VelocityField::evaluate(const FieldCoefficients& c, Point p) const { return evaluate_impl<false>(c, p, nullptr); }

Point VelocityField::evaluate(const FieldCoefficients& c, Point p, FieldGradient& gradient) const {
  return evaluate_impl<true>(c, p, &gradient);
}

Point VelocityField::operator()(Point p, double t) const {
  FieldCoefficients c;
  coefficients(t, c);
  return evaluate(c, p);
}

}  // namespace texwarp
