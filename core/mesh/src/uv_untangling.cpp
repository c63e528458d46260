// Untangling UVs with the regularised barrier energy of Garanzha et al. 2021: see uv_untangling.hpp.
#include "texwarp/mesh/uv_untangling.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include <LBFGS.h>
#include <Eigen/Core>

#include "texwarp/mesh/surface_jacobian.hpp"

namespace texwarp::mesh {
namespace {

// χ(D, ε) = (D + √(ε² + D²)) / 2, in the form that does not cancel for D < 0; and dχ/dD = χ / √(ε² + D²).
double chi(double det, double eps) {
  const double root = std::sqrt(eps * eps + det * det);
  return det > 0.0 ? 0.5 * (det + root) : 0.5 * eps * eps / (root - det);
}

// The energy of one local untangling: the vertices not `held` move; the triangles with a moving corner are the
// active ones, and the others add a constant (per ε) so that the energy, and the ε schedule read from it, are the
// whole region's.
class Untangler {
 public:
  Untangler(const TriangleMesh& mesh, std::span<const SurfaceTriangle> triangles, std::span<const Point> uv,
            const std::vector<char>& held, const UvTriangleCheck& acceptable, double area_weight)
      : mesh_(mesh),
        triangles_(triangles),
        start_(uv.begin(), uv.end()),
        acceptable_(acceptable),
        area_weight_(area_weight) {
    unknown_.assign(uv.size(), -1);
    for (std::size_t v = 0; v < uv.size(); ++v) {
      if (!held[v]) unknown_[v] = free_++;
    }
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      total_area_ += triangles_[i].area;
      if (triangles_[i].area == 0.0) continue;
      const Face& f = mesh.faces[i];
      if (unknown_[f[0]] >= 0 || unknown_[f[1]] >= 0 || unknown_[f[2]] >= 0) {
        active_.push_back(i);
      } else {
        still_.push_back(i);
      }
    }
  }

  Eigen::VectorXd unknowns(std::span<const Point> uv) const {
    Eigen::VectorXd x(2 * free_);
    for (std::size_t v = 0; v < uv.size(); ++v) {
      if (unknown_[v] < 0) continue;
      x[unknown_[v]] = uv[v].real();
      x[free_ + unknown_[v]] = uv[v].imag();
    }
    return x;
  }

  std::vector<Point> positions(const Eigen::VectorXd& x) const {
    std::vector<Point> uv = start_;
    for (std::size_t v = 0; v < uv.size(); ++v) {
      if (unknown_[v] >= 0) uv[v] = Point(x[unknown_[v]], x[free_ + unknown_[v]]);
    }
    return uv;
  }

  int rejected(std::span<const Point> uv) const {
    return static_cast<int>(std::count_if(mesh_.faces.begin(), mesh_.faces.end(),
                                          [&](const Face& f) { return !acceptable_(uv[f[0]], uv[f[1]], uv[f[2]]); }));
  }

  // A triangle's term of Σ A (…) (see energy).
  double triangle_energy(const Jacobian& j, double eps) const {
    const double det = j.det();
    const double c = chi(det, eps);
    const double frob = j.a * j.a + j.b * j.b + j.c * j.c + j.d * j.d;
    return (1.0 - area_weight_) * frob / c + area_weight_ * (det * det + 1.0) / c;
  }

  // The smallest determinant over triangles of positive surface area.
  double min_det(std::span<const Point> uv) const {
    double lowest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      if (triangles_[i].area > 0.0) lowest = std::min(lowest, jacobian(triangles_[i], mesh_.faces[i], uv).det());
    }
    return lowest;
  }

  // F_ε per unit area: Σ A ((1 − λ) ‖J‖² / χ(D, ε) + λ (D² + 1) / χ(D, ε)) / Σ A, and its gradient in x.
  double energy(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, double eps) const {
    if (gradient) gradient->setZero(x.size());
    if (eps != still_eps_) {
      still_eps_ = eps;
      still_energy_ = 0.0;
      for (const std::size_t i : still_) {
        still_energy_ += triangles_[i].area * triangle_energy(jacobian(triangles_[i], mesh_.faces[i], start_), eps);
      }
    }
    double sum = still_energy_;
    const double shape = 1.0 - area_weight_;
    for (const std::size_t i : active_) {
      const SurfaceTriangle& t = triangles_[i];
      const Face& f = mesh_.faces[i];
      std::array<Point, 3> corner{};
      for (int k = 0; k < 3; ++k) {
        const int u = unknown_[f[k]];
        corner[k] = u < 0 ? start_[f[k]] : Point(x[u], x[free_ + u]);
      }
      const Jacobian j = jacobian(t, Face{0, 1, 2}, corner);
      const double det = j.det();
      const double root = std::sqrt(eps * eps + det * det);
      const double c = chi(det, eps);
      const double frob = j.a * j.a + j.b * j.b + j.c * j.c + j.d * j.d;
      const double f_shape = frob / c, f_area = (det * det + 1.0) / c;
      sum += t.area * (shape * f_shape + area_weight_ * f_area);
      if (!gradient) continue;
      // dE/dJ = A ((1 − λ)(2J − f_shape χ' cof J) + λ (2D − f_area χ') cof J) / χ, cof J = ∂D/∂J = [[d, −c], [−b, a]],
      // χ' = χ / root.
      const double dchi = c / root;
      const double along_cof = (-shape * f_shape * dchi + area_weight_ * (2.0 * det - f_area * dchi)) / c;
      const double own = 2.0 * shape / c;
      const double ga = t.area * (own * j.a + along_cof * j.d);
      const double gb = t.area * (own * j.b - along_cof * j.c);
      const double gc = t.area * (own * j.c - along_cof * j.b);
      const double gd = t.area * (own * j.d + along_cof * j.a);
      for (int k = 0; k < 3; ++k) {
        const int u = unknown_[f[k]];
        if (u < 0) continue;
        (*gradient)[u] += (ga * t.gx[k] + gb * t.gy[k]) / total_area_;
        (*gradient)[free_ + u] += (gc * t.gx[k] + gd * t.gy[k]) / total_area_;
      }
    }
    return sum / total_area_;
  }

 private:
  const TriangleMesh& mesh_;
  std::span<const SurfaceTriangle> triangles_;
  std::vector<Point> start_;
  const UvTriangleCheck& acceptable_;
  double area_weight_;
  std::vector<int> unknown_;  // per vertex: its index among the free ones, −1 when held
  int free_ = 0;
  std::vector<std::size_t> active_;  // triangles of positive area with a free corner
  std::vector<std::size_t> still_;   // the other triangles of positive area: a constant term
  double total_area_ = 0.0;
  mutable double still_eps_ = -1.0;  // the ε still_energy_ was summed for
  mutable double still_energy_ = 0.0;
};

// F_ε for LBFGSpp, remembering the lowest point it was asked about (a line search that gives up leaves x at its
// last trial).
struct RoundObjective {
  RoundObjective(const Untangler& u, double e) : untangler(u), eps(e) {}

  const Untangler& untangler;
  double eps;
  double best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_x;

  double operator()(const Eigen::VectorXd& x, Eigen::VectorXd& gradient) {
    const double e = untangler.energy(x, &gradient, eps);
    if (std::isfinite(e) && e < best) {
      best = e;
      best_x = x;
    }
    return e;
  }
};

// Rounds of ε on `untangler`'s free vertices from `uv`, at most `max_rounds`; `uv` is replaced by the result with the
// fewest refused triangles when that is fewer than at the start. Returns (rounds run, refused in `uv` after).
std::pair<int, int> untangle_rounds(const Untangler& untangler, std::span<Point> uv, int max_rounds,
                                    const UvUntanglingOptions& options, const RunControl& control) {
  Eigen::VectorXd x = untangler.unknowns(uv);
  std::vector<Point> kept;  // the result with the fewest refused triangles so far
  int kept_rejected = untangler.rejected(uv);
  const int start_rejected = kept_rejected;
  int last_gain = 0;  // the round that last lowered the refused count
  double det_min = untangler.min_det(uv);
  // The first ε: the paper's (the most inverted triangle counts as if it had a small positive area), but at most the
  // mean determinant, 1 (the surface is scaled to the UVs' area). A start from a fold-free warp has a few badly
  // inverted triangles among many good ones, and a larger ε reshapes the good ones too: on the pinned-unwrap
  // benchmark the paper's choice (ε up to 3.5) untangled 60 of 72 cases, ε ≤ 1 and ε ≤ 0.5 63, ε ≤ 0.1 fewer.
  double eps = std::min(std::sqrt(1e-8 + 0.04 * std::pow(std::min(det_min, 0.0), 2)), 1.0);
  double before = untangler.energy(x, nullptr, eps);

  LBFGSpp::LBFGSParam<double> param;
  param.m = 8;
  // Each round runs to a standstill (the energy's relative change over 3 iterations below 1e-9) or its step bound:
  // a gradient test relative to ‖x‖ (pixel positions, large) would end rounds long before.
  param.epsilon = 1e-12;
  param.epsilon_rel = 0.0;
  param.past = 3;
  param.delta = 1e-9;
  param.max_iterations = options.max_steps_per_round;
  LBFGSpp::LBFGSSolver<double> solver(param);
  int rounds = 0;
  while (rounds < max_rounds) {
    if (control.canceled()) throw CanceledError();
    RoundObjective objective(untangler, eps);
    double fx = 0.0;
    try {
      solver.minimize(objective, x, fx);
    } catch (const std::exception&) {
      // The line search found no lower point along the last direction (runtime_error), or the quasi-Newton direction
      // stopped being one of descent (logic_error): the lowest point seen stands, and the next round starts afresh.
    }
    if (objective.best_x.size() == x.size()) x = objective.best_x;
    ++rounds;
    const double after = untangler.energy(x, nullptr, eps);
    const std::vector<Point> now = untangler.positions(x);
    const int refused = untangler.rejected(now);
    if (refused < kept_rejected) {
      last_gain = rounds;
      kept = now;
      kept_rejected = refused;
    }
    det_min = untangler.min_det(now);
    // Done once nothing is refused: evening the triangles out is the UV optimisation's work, which follows (SLIM's
    // symmetric Dirichlet energy does it in a few iterations where this energy's barrier takes many rounds; on the
    // pinned-unwrap benchmark ten more rounds here changed no figure). Given up when the refused count has not
    // fallen for `patience` rounds.
    if (refused == 0 && det_min > 0.0) break;
    if (rounds - last_gain >= options.patience) break;
    // The paper's schedule: the worst triangle's χ falls by (1 − σ), σ the last round's relative decrease (≥ 1/10).
    const double sigma = std::max(1.0 - after / before, 0.1);
    const double mu = (1.0 - sigma) * chi(det_min, eps);
    eps = det_min < mu ? 2.0 * std::sqrt(mu * (mu - det_min)) : 1e-12;
    before = untangler.energy(x, nullptr, eps);
  }
  if (!kept.empty() && kept_rejected < start_rejected) std::copy(kept.begin(), kept.end(), uv.begin());
  return {rounds, kept_rejected};
}

// Per vertex: 1 unless it is within `rings` edges of a corner of a triangle `acceptable` refuses (or `rings` < 0:
// none is held) or it is in `fixed`.
std::vector<char> held_outside_rings(const TriangleMesh& mesh, std::span<const Point> uv, std::span<const int> fixed,
                                     const UvTriangleCheck& acceptable, int rings,
                                     const std::vector<std::vector<int>>& neighbours) {
  const std::size_t n = uv.size();
  std::vector<char> held(n, rings < 0 ? 0 : 1);
  if (rings >= 0) {
    std::vector<int> frontier;
    for (const Face& f : mesh.faces) {
      if (acceptable(uv[f[0]], uv[f[1]], uv[f[2]])) continue;
      for (const int v : f) {
        if (held[v]) {
          held[v] = 0;
          frontier.push_back(v);
        }
      }
    }
    for (int ring = 0; ring < rings && !frontier.empty(); ++ring) {
      std::vector<int> next;
      for (const int v : frontier) {
        for (const int w : neighbours[v]) {
          if (held[w]) {
            held[w] = 0;
            next.push_back(w);
          }
        }
      }
      frontier = std::move(next);
    }
  }
  for (const int v : fixed) held[v] = 1;
  return held;
}

}  // namespace

UvUntangling untangle_uvs(const TriangleMesh& mesh, std::span<Point> uv, std::span<const int> fixed,
                          const UvTriangleCheck& acceptable, const UvUntanglingOptions& options,
                          const RunControl& control) {
  UvUntangling out;
  out.rejected_before = static_cast<int>(std::count_if(
      mesh.faces.begin(), mesh.faces.end(), [&](const Face& f) { return !acceptable(uv[f[0]], uv[f[1]], uv[f[2]]); }));
  out.rejected_after = out.rejected_before;
  if (out.rejected_before == 0) return out;
  const std::vector<SurfaceTriangle> triangles = surface_triangles(mesh, uv);  // the scale of the start's UVs
  double total_area = 0.0;
  for (const SurfaceTriangle& t : triangles) total_area += t.area;
  if (!(total_area > 0.0)) return out;
  std::vector<std::vector<int>> neighbours(uv.size());
  if (options.rings >= 0) {
    for (const Face& f : mesh.faces) {
      for (int k = 0; k < 3; ++k) {
        neighbours[f[k]].push_back(f[(k + 1) % 3]);
        neighbours[f[k]].push_back(f[(k + 2) % 3]);
      }
    }
  }
  std::vector<char> is_fixed(uv.size(), 0);
  for (const int v : fixed) is_fixed[v] = 1;
  const auto movable = static_cast<std::size_t>(std::count(is_fixed.begin(), is_fixed.end(), 0));

  // Around the refused triangles first, `rings` edges out, then twice as far each time refused triangles remain,
  // until every vertex not in `fixed` moves: the cost of a round follows the tangle's size, not the region's.
  // (A part of the region that no ring reaches, its own component, never moves: then the growth stops too.)
  std::vector<Point> current(uv.begin(), uv.end());
  int refused = out.rejected_before;
  std::vector<char> last_held;  // the last try's
  for (int rings = options.rings; out.rounds < options.max_rounds; rings = std::max(2 * rings, 1)) {
    std::vector<char> held = held_outside_rings(mesh, current, fixed, acceptable, rings, neighbours);
    if (held == last_held) break;  // the rings reach no further
    const auto moving = static_cast<std::size_t>(std::count(held.begin(), held.end(), 0));
    const bool whole = moving == movable;
    if (moving > 0) {
      const Untangler untangler(mesh, triangles, current, held, acceptable, options.area_weight);
      const auto [rounds, after] =
          untangle_rounds(untangler, current, options.max_rounds - out.rounds, options, control);
      out.rounds += rounds;
      refused = after;
    }
    if (refused == 0 || whole) break;
    last_held = std::move(held);
  }
  if (refused < out.rejected_before) {
    std::copy(current.begin(), current.end(), uv.begin());
    out.rejected_after = refused;
    out.applied = true;
  }
  return out;
}

}  // namespace texwarp::mesh
