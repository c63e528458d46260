// SLIM on the symmetric Dirichlet energy with fixed pins: see uv_optimization.hpp.
#include "texwarp/mesh/uv_optimization.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include "sparse_cholesky.hpp"
#include "texwarp/core/numerical_error.hpp"
#include "texwarp/mesh/surface_jacobian.hpp"

namespace texwarp::mesh {
namespace {

// σ1/σ2 (∞ when det ≤ 0).
double aspect(const Jacobian& j) {
  const double q = std::hypot(0.5 * (j.a + j.d), 0.5 * (j.c - j.b));
  const double r = std::hypot(0.5 * (j.a - j.d), 0.5 * (j.c + j.b));
  return j.det() > 0.0 && q > r ? (q + r) / (q - r) : std::numeric_limits<double>::infinity();
}

// ‖J‖² + ‖J⁻¹‖² (∞ when det ≤ 0).
double symmetric_dirichlet(const Jacobian& j) {
  const double det = j.det();
  if (!(det > 0.0)) return std::numeric_limits<double>::infinity();
  const double frob = j.a * j.a + j.b * j.b + j.c * j.c + j.d * j.d;
  return frob + frob / (det * det);
}

// Smallest α > 0 with det(J + α dJ) = 0, or +∞.
double first_degenerate_step(const Jacobian& j, const Jacobian& dj) {
  const double qa = dj.det();
  const double qb = j.a * dj.d + dj.a * j.d - j.b * dj.c - dj.b * j.c;
  const double qc = j.det();
  double best = std::numeric_limits<double>::infinity();
  const auto take = [&best](double root) {
    if (root > 0.0 && root < best) best = root;
  };
  if (std::abs(qa) <= 1e-14 * (std::abs(qb) + std::abs(qc))) {
    if (qb != 0.0) take(-qc / qb);
    return best;
  }
  const double disc = qb * qb - 4.0 * qa * qc;
  if (disc < 0.0) return best;
  const double s = std::sqrt(disc);
  // Stable roots: q = −(b + sign(b)·√disc)/2, roots q/a and c/q.
  const double q = -0.5 * (qb + std::copysign(s, qb));
  if (q != 0.0) {
    take(q / qa);
    take(qc / q);
  }
  return best;
}

// The most distorted triangle's energy density and σ1/σ2 (each its own triangle's).
struct Worst {
  double energy = std::numeric_limits<double>::infinity();
  double aspect = std::numeric_limits<double>::infinity();
};

// Conjugate-gradient iterations a global step's solve may take: preconditioned with the coupled factor of an
// earlier iteration, or with the u–u and v–v blocks' factors.
constexpr int kMaxPreconditionedIterations = 25;
constexpr int kMaxBlockIterations = 60;

class Slim {
 public:
  Slim(const TriangleMesh& mesh, std::span<Point> uv, std::span<const int> fixed, const UvTriangleCheck& acceptable)
      : mesh_(mesh), uv_(uv), acceptable_(acceptable) {
    const int n = mesh.vertex_count();
    unknown_.assign(static_cast<std::size_t>(n), 0);
    for (int v : fixed) unknown_[v] = -1;
    for (int v = 0; v < n; ++v) {
      if (unknown_[v] == 0) unknown_[v] = free_++;
    }
    triangles_ = surface_triangles(mesh, uv);
    for (const SurfaceTriangle& t : triangles_) total_area_ += t.area;
  }

  double energy(std::span<const Point> uv, Worst* worst = nullptr) const {
    double sum = 0.0;
    Worst most{0.0, 0.0};
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      if (triangles_[i].area == 0.0) continue;
      const Jacobian j = jacobian(triangles_[i], mesh_.faces[i], uv);
      const double e = symmetric_dirichlet(j);
      sum += triangles_[i].area * e;
      if (worst) {
        most.energy = std::max(most.energy, e);
        most.aspect = std::max(most.aspect, aspect(j));
      }
    }
    if (worst) *worst = most;
    return total_area_ > 0.0 ? sum / total_area_ : 0.0;
  }

  // The most a triangle may be distorted after a step (see UvOptimizationOptions::max_aspect).
  void hold_worst(const Worst& worst) { worst_ = worst; }

  bool all_acceptable(std::span<const Point> uv) const {
    return std::all_of(mesh_.faces.begin(), mesh_.faces.end(),
                       [&](const Face& f) { return acceptable_(uv[f[0]], uv[f[1]], uv[f[2]]); });
  }

  // One local/global step and its line search; false when no step lowers the energy.
  bool step(double& energy_now) {
    if (free_ == 0 || total_area_ == 0.0) return false;
    const Eigen::VectorXd target = global_solve();
    std::vector<Point> direction(uv_.size(), Point(0.0, 0.0));
    for (int v = 0; v < static_cast<int>(uv_.size()); ++v) {
      if (unknown_[v] >= 0) direction[v] = Point(target[unknown_[v]], target[free_ + unknown_[v]]) - uv_[v];
    }
    double alpha = 1.0;
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      const Face& f = mesh_.faces[i];
      if (triangles_[i].area == 0.0) continue;
      alpha = std::min(
          alpha, 0.8 * first_degenerate_step(jacobian(triangles_[i], f, uv_), jacobian(triangles_[i], f, direction)));
    }
    std::vector<Point> trial(uv_.begin(), uv_.end());
    for (int halvings = 0; halvings < 40; ++halvings, alpha *= 0.5) {
      for (std::size_t v = 0; v < trial.size(); ++v) trial[v] = uv_[v] + alpha * direction[v];
      Worst worst;
      const double e = energy(trial, &worst);
      if (e < energy_now && worst.energy <= worst_.energy && worst.aspect <= worst_.aspect && all_acceptable(trial)) {
        std::copy(trial.begin(), trial.end(), uv_.begin());
        energy_now = e;
        return true;
      }
    }
    return false;
  }

 private:
  // The global step: argmin Σ A ‖W (J − R)‖² over the free vertices (u then v), with per triangle R the closest
  // rotation to J and W = U diag(w) Uᵀ from J = U Σ Vᵀ, w_i = √(ψ'(σ_i) / 2(σ_i − 1)) for ψ(σ) = σ² + σ⁻², i.e.
  // w_i² = (σ_i + 1)(σ_i² + 1) / σ_i³ (Rabinovich et al. 2017, §4). A small proximal term keeps it definite.
  // The normal matrix is assembled into a sparsity pattern built once (each triangle's 6×6 block summed into the
  // values it owns: no triplet list of 144 entries per triangle per iteration). It is solved by conjugate gradients
  // preconditioned with the factors of its u–u and v–v blocks (block_solve); where that does not converge (a map far
  // from a similarity couples u and v strongly), the coupled matrix is factorised, and later iterations solve by
  // conjugate gradients preconditioned with that factor (the weights change little from one iteration to the next),
  // factorising again only when that does not converge.
  Eigen::VectorXd global_solve() {
    const int m = 2 * free_;
    if (!analysed_) build_pattern();
    std::fill(normal_.valuePtr(), normal_.valuePtr() + normal_.nonZeros(), 0.0);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(m);
    Eigen::VectorXd current(m);  // the free vertices' UVs now: the solve's start
    const double proximal = 1e-8 * total_area_ / static_cast<double>(std::max<std::size_t>(triangles_.size(), 1));
    double* values = normal_.valuePtr();
    for (int v = 0; v < static_cast<int>(uv_.size()); ++v) {
      const int k = unknown_[v];
      if (k < 0) continue;
      values[diagonal_[k]] += proximal;
      values[diagonal_[free_ + k]] += proximal;
      rhs[k] += proximal * uv_[v].real();
      rhs[free_ + k] += proximal * uv_[v].imag();
      current[k] = uv_[v].real();
      current[free_ + k] = uv_[v].imag();
    }
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      const SurfaceTriangle& t = triangles_[i];
      if (t.area == 0.0) continue;
      const Face& f = mesh_.faces[i];
      const Jacobian j = jacobian(t, f, uv_);
      // 2×2 SVD in closed form: J = Rot(φ) diag(σ1, σ2) Rot(θ), σ1 ≥ |σ2|, det > 0 so σ2 > 0.
      const double e = 0.5 * (j.a + j.d), ff = 0.5 * (j.a - j.d), g = 0.5 * (j.c + j.b), h = 0.5 * (j.c - j.b);
      const double q = std::hypot(e, h), r = std::hypot(ff, g);
      const double s1 = q + r, s2 = q - r;
      const double a1 = std::atan2(g, ff), a2 = std::atan2(h, e);
      const double phi = 0.5 * (a2 + a1);
      const auto weight = [](double s) { return std::sqrt((s + 1.0) * (s * s + 1.0) / (s * s * s)); };
      const double w1 = weight(s1), w2 = weight(std::max(s2, 1e-12));
      const double cp = std::cos(phi), sp = std::sin(phi);
      // W = U diag(w1, w2) Uᵀ, U = Rot(φ).
      const double w11 = w1 * cp * cp + w2 * sp * sp, w22 = w1 * sp * sp + w2 * cp * cp;
      const double w12 = (w1 - w2) * cp * sp;
      // R = Rot(a2): the closest rotation to J.
      const double rc = std::cos(a2), rs = std::sin(a2);
      const double rot[2][2] = {{rc, -rs}, {rs, rc}};
      const double w[2][2] = {{w11, w12}, {w12, w22}};
      const double sqrt_area = std::sqrt(t.area);
      const int* slots = &slots_[i * 36];
      for (const auto& w_row : w) {
        for (int col = 0; col < 2; ++col) {
          // Residual √A (w_row,0 ∇_col u + w_row,1 ∇_col v − (W R)_row,col).
          const std::array<double, 3>& grad = col == 0 ? t.gx : t.gy;
          const double goal = sqrt_area * (w_row[0] * rot[0][col] + w_row[1] * rot[1][col]);
          std::array<int, 6> var{};
          std::array<double, 6> coef{};
          std::array<double, 6> known{};
          for (int k = 0; k < 3; ++k) {
            const int v = f[k];
            var[k] = unknown_[v] < 0 ? -1 : unknown_[v];
            var[3 + k] = unknown_[v] < 0 ? -1 : free_ + unknown_[v];
            coef[k] = sqrt_area * w_row[0] * grad[k];
            coef[3 + k] = sqrt_area * w_row[1] * grad[k];
            known[k] = uv_[v].real();
            known[3 + k] = uv_[v].imag();
          }
          double fixed_part = 0.0;
          for (int x = 0; x < 6; ++x) {
            if (var[x] < 0) fixed_part += coef[x] * known[x];
          }
          for (int x = 0; x < 6; ++x) {
            if (var[x] < 0) continue;
            rhs[var[x]] += coef[x] * (goal - fixed_part);
            for (int y = 0; y < 6; ++y) {
              if (var[y] >= 0 && var[x] >= var[y]) values[slots[x * 6 + y]] += coef[x] * coef[y];
            }
          }
        }
      }
    }
    Eigen::VectorXd x = current;
    if (!factorised_ && block_solve(rhs, x)) return x;
    x = current;
    if (!factorised_ || !preconditioned_solve(rhs, x, kMaxPreconditionedIterations,
                                              [this](const Eigen::VectorXd& r) { return solver_.solve(r); })) {
      solver_.factorize(normal_);
      if (solver_.info() != Eigen::Success) {
        throw NumericalError("UV optimisation: the global step's matrix is singular");
      }
      factorised_ = true;
      x = solver_.solve(rhs);
    }
    if (solver_.info() != Eigen::Success || !x.allFinite()) {
      throw NumericalError("UV optimisation: the global step's solve failed");
    }
    return x;
  }

  // Conjugate gradients preconditioned with the u–u and v–v blocks of the normal matrix, each factorised on its own:
  // the u–v coupling, W's off-diagonal (w1 − w2)·cos φ·sin φ, is small wherever the map is near a similarity, and
  // two factors of half the size cost a fraction of the coupled one's (a quarter of its flops on a mesh, or less).
  // False (x undefined) when the blocks cannot be factorised or the solve does not converge: the coupled factor
  // then takes over for the rest of the run.
  bool block_solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) {
    const Eigen::Index n = free_;
    const Eigen::SparseMatrix<double> uu = normal_.topLeftCorner(n, n);
    const Eigen::SparseMatrix<double> vv = normal_.bottomRightCorner(n, n);
    if (!block_analysed_) {
      u_solver_.analyzePattern(uu);
      v_solver_.analyzePattern(vv);
      block_analysed_ = true;
    }
    u_solver_.factorize(uu);
    v_solver_.factorize(vv);
    if (u_solver_.info() != Eigen::Success || v_solver_.info() != Eigen::Success) return false;
    return preconditioned_solve(rhs, x, kMaxBlockIterations, [this, n](const Eigen::VectorXd& r) {
      Eigen::VectorXd z(r.size());
      z.head(n) = u_solver_.solve(r.head(n));
      z.tail(n) = v_solver_.solve(r.tail(n));
      return z;
    });
  }

  // The normal matrix's pattern, its lower triangle (what the Cholesky factorisation reads): every pair of free
  // unknowns of a triangle, u and v; analysed once. For each triangle, the index in the matrix's values of each of
  // its 6×6 pairs in the lower triangle (−1 where either is fixed or the pair is above the diagonal).
  void build_pattern() {
    const int m = 2 * free_;
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(triangles_.size() * 36 + static_cast<std::size_t>(m));
    for (int k = 0; k < m; ++k) entries.emplace_back(k, k, 0.0);
    const auto vars = [&](const Face& f) {
      std::array<int, 6> var{};
      for (int k = 0; k < 3; ++k) {
        var[k] = unknown_[f[k]] < 0 ? -1 : unknown_[f[k]];
        var[3 + k] = unknown_[f[k]] < 0 ? -1 : free_ + unknown_[f[k]];
      }
      return var;
    };
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      if (triangles_[i].area == 0.0) continue;
      const std::array<int, 6> var = vars(mesh_.faces[i]);
      for (int x : var) {
        for (int y : var) {
          if (y >= 0 && x >= y) entries.emplace_back(x, y, 0.0);
        }
      }
    }
    normal_.resize(m, m);
    normal_.setFromTriplets(entries.begin(), entries.end());
    normal_.makeCompressed();
    const auto slot = [&](int row, int col) {
      const int* begin = normal_.innerIndexPtr() + normal_.outerIndexPtr()[col];
      const int* end = normal_.innerIndexPtr() + normal_.outerIndexPtr()[col + 1];
      return static_cast<int>(std::lower_bound(begin, end, row) - normal_.innerIndexPtr());
    };
    diagonal_.resize(static_cast<std::size_t>(m));
    for (int k = 0; k < m; ++k) diagonal_[k] = slot(k, k);
    slots_.assign(triangles_.size() * 36, -1);
    for (std::size_t i = 0; i < triangles_.size(); ++i) {
      if (triangles_[i].area == 0.0) continue;
      const std::array<int, 6> var = vars(mesh_.faces[i]);
      for (std::size_t x = 0; x < 6; ++x) {
        for (std::size_t y = 0; y < 6; ++y) {
          if (var[y] >= 0 && var[x] >= var[y]) slots_[i * 36 + x * 6 + y] = slot(var[x], var[y]);
        }
      }
    }
    solver_.analyzePattern(normal_);
    analysed_ = true;
  }

  // Conjugate gradients on normal_ x = rhs from x, preconditioned with `precondition` (z = M⁻¹ r); true when the
  // residual fell below 1e-7 of rhs's norm (a descent direction for the line search, far below what moves a UV)
  // within `max_iterations`.
  template <class Preconditioner>
  bool preconditioned_solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x, int max_iterations,
                            const Preconditioner& precondition) const {
    const double goal = 1e-7 * rhs.norm();
    Eigen::VectorXd r = rhs - normal_.selfadjointView<Eigen::Lower>() * x;
    const double start = r.norm();
    if (start <= goal) return true;
    Eigen::VectorXd z = precondition(r);
    Eigen::VectorXd p = z;
    double rz = r.dot(z);
    for (int it = 0; it < max_iterations; ++it) {
      const Eigen::VectorXd ap = normal_.selfadjointView<Eigen::Lower>() * p;
      const double pap = p.dot(ap);
      if (!(pap > 0.0)) return false;
      const double alpha = rz / pap;
      x += alpha * p;
      r -= alpha * ap;
      if (r.norm() <= goal) return x.allFinite();
      // Every 10 iterations: give up early when the mean rate so far would not reach the goal in time.
      const int done = it + 1;
      if (done % 10 == 0 && done < max_iterations) {
        const double rate = std::pow(r.norm() / start, 1.0 / done);
        if (!(rate < 1.0) || std::pow(rate, max_iterations - done) * r.norm() > goal) return false;
      }
      z = precondition(r);
      const double rz_next = r.dot(z);
      p = z + (rz_next / rz) * p;
      rz = rz_next;
    }
    return false;
  }

  const TriangleMesh& mesh_;
  std::span<Point> uv_;
  const UvTriangleCheck& acceptable_;
  std::vector<int> unknown_;  // per vertex: its index among the free ones, −1 when fixed
  int free_ = 0;
  std::vector<SurfaceTriangle> triangles_;
  double total_area_ = 0.0;
  Worst worst_;                         // the most a triangle's energy density and σ1/σ2 may reach
  Eigen::SparseMatrix<double> normal_;  // the global step's normal matrix (lower triangle), pattern fixed once
  std::vector<int> diagonal_;           // per unknown: its diagonal's index in normal_'s values
  std::vector<int> slots_;              // per triangle, 36: the values its 6×6 block adds to (−1: none)
  SparseCholesky solver_;               // the coupled normal matrix's factor
  SparseCholesky u_solver_;             // its u–u block's (block_solve)
  SparseCholesky v_solver_;             // its v–v block's
  bool analysed_ = false;
  bool block_analysed_ = false;
  bool factorised_ = false;  // the coupled factor exists: block_solve is not tried again
};

}  // namespace

UvOptimization optimize_uvs(const TriangleMesh& mesh, std::span<Point> uv, std::span<const int> fixed,
                            const UvTriangleCheck& acceptable, const UvOptimizationOptions& options) {
  Slim slim(mesh, uv, fixed, acceptable);
  if (!slim.all_acceptable(uv)) throw NumericalError("UV optimisation needs a start without flipped triangles");
  UvOptimization out;
  Worst worst;
  out.energy_before = slim.energy(uv, &worst);
  worst.aspect = std::max(worst.aspect, options.max_aspect);
  if (options.limit_worst) slim.hold_worst(worst);
  out.energy_after = out.energy_before;
  while (out.iterations < options.max_iterations) {
    const double before = out.energy_after;
    if (!slim.step(out.energy_after)) {
      out.converged = true;
      break;
    }
    ++out.iterations;
    if (before - out.energy_after < options.relative_decrease * before) {
      out.converged = true;
      break;
    }
  }
  return out;
}

}  // namespace texwarp::mesh
