// The trajectory planner: straight lines, a repair, or the sweep: see trajectory_planner.hpp.
//
// The sweep, in coordinates rotated so that the x axis is a direction where the projections are well spread:
//   W0 = sources (x_i, y_i) → W1 = (X_i, y_i) → W2 = (X_i, h_i) → W3 = (X'_i, h_i) → W4 = (X'_i, y'_i) → W5 = targets.
// X is an order-preserving expansion of the x_i whose gaps are ≥ g (X_i = x_i + e_i, e non-decreasing in x): in
// phase 1 every pair's x distance only grows while its y distance stays, so no pair comes closer than it starts.
// Phase 2 moves only vertically at x coordinates ≥ g apart, phase 3 only horizontally at heights h_i ≥ g apart,
// phase 4 vertically again, phase 5 is phase 1 of the targets backwards. So the plan keeps min(g, the sources'
// and the targets' own minimum distances) for ANY distinct sources and distinct targets. Segments without motion
// are dropped. The intermediate waypoints are then relaxed toward the straight interpolation where separation
// allows (bisection per waypoint).
//
// Energy. A pair's field turns and scales its surroundings at the rate c_ij = ΔD_ij / ΔF_ij(t) (Eq. 2); two features
// that pass close turn the texture between them by up to π in the short time they are close, a twist that neither
// the pixels nor a mesh's straight edges resolve. The plan's energy Σ_segments Σ_pairs ∫ |c_ij|² dt charges a pass
// at distance d and relative speed s about π·s/d; per pair and straight segment it is exact in closed form,
// |b − a|²·φ / (|a|·|b|·sin φ) with a, b the pair's offset at the segment's ends and φ the angle between them
// (∫ |δ|² / |a + s·δ|² ds). Interior waypoints are moved to lower it (lower_plan_energy) after the plan is found.
//
// Distortion proxy (to choose among valid plans): Σ over segments of max over pairs of |ΔD_ij| / d_ij, d_ij the
// pair's exact closest approach in the segment: a bound on ∫ max |c_ij(t)| dt, the rate at which the pair fields
// (Eq. 2–3) scale and rotate, i.e. on the log of the local stretch the warp can reach.
#include "texwarp/core/trajectory_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "texwarp/core/trajectory_segment.hpp"

namespace texwarp {
namespace {

using Configuration = std::vector<Point>;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Candidate directions of the sweep, and how many of the best spread ones are tried in full.
constexpr int kSweepDirections = 36;
constexpr int kSweepCandidates = 3;
// Relaxation: bisection steps per waypoint.
constexpr int kBisectionSteps = 12;
// Repair: intermediate configurations tried, and the pair budget of its iterations.
constexpr int kRepairIterations = 400;
constexpr double kRepairPairBudget = 4e7;
// Energy lowering: segments given to a straight plan, pairs within this many length scales, iterations, and the
// pair evaluations of all its iterations.
constexpr std::size_t kEnergySegments = 4;
constexpr double kEnergyReach = 4.0;
constexpr int kEnergyIterations = 400;
constexpr double kEnergyPairBudget = 1e7;
// A straight plan whose pairs pass closer than this share of the length scale is lowered too.
constexpr double kEnergyNearMiss = 0.25;

// Each point's box over a segment a → b (it moves straight from a_i to b_i), and the points in the order of their
// boxes' left edges. Two points are never closer in the segment than their boxes' gap along x or along y.
struct SweptBoxes {
  std::vector<double> x0, x1, y0, y1;
  std::vector<std::size_t> order;
};

SweptBoxes swept_boxes(const Configuration& a, const Configuration& b) {
  const std::size_t n = a.size();
  SweptBoxes boxes;
  boxes.x0.resize(n);
  boxes.x1.resize(n);
  boxes.y0.resize(n);
  boxes.y1.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    boxes.x0[i] = std::min(a[i].real(), b[i].real());
    boxes.x1[i] = std::max(a[i].real(), b[i].real());
    boxes.y0[i] = std::min(a[i].imag(), b[i].imag());
    boxes.y1[i] = std::max(a[i].imag(), b[i].imag());
  }
  boxes.order.resize(n);
  std::iota(boxes.order.begin(), boxes.order.end(), std::size_t{0});
  std::sort(boxes.order.begin(), boxes.order.end(), [&](std::size_t i, std::size_t j) {
    return boxes.x0[i] < boxes.x0[j] || (boxes.x0[i] == boxes.x0[j] && i < j);
  });
  return boxes;
}

// Calls visit(i, j), i < j, for every pair whose boxes' gap is below reach(i) along both axes (sort and sweep on x):
// every pair not visited stays at least reach(i) apart over the segment. reach(i) may only shrink as visits go on.
template <typename Reach, typename Visit>
void for_each_near_pair(const SweptBoxes& boxes, Reach&& reach, Visit&& visit) {
  const std::vector<std::size_t>& o = boxes.order;
  for (std::size_t p = 0; p < o.size(); ++p) {
    const std::size_t i = o[p];
    for (std::size_t r = p + 1; r < o.size(); ++r) {
      const std::size_t j = o[r];
      const double within = reach(i);
      if (boxes.x0[j] - boxes.x1[i] >= within) break;  // later boxes start further right still
      if (std::max(boxes.y0[j] - boxes.y1[i], boxes.y0[i] - boxes.y1[j]) >= within) continue;
      visit(std::min(i, j), std::max(i, j));
    }
  }
}

// The smallest closest approach over all pairs (exact: a pair whose boxes are at least the best found apart cannot
// come closer).
double segment_min_separation(const Configuration& a, const Configuration& b) {
  double best = kInf;
  for_each_near_pair(
      swept_boxes(a, b), [&](std::size_t) { return best; },
      [&](std::size_t i, std::size_t j) {
        best = std::min(best, straight_closest_approach(a[i], b[i] - a[i], a[j], b[j] - a[j]).distance);
      });
  return best;
}

// max over pairs of |ΔD_ij| / d_ij (exact: |ΔD_ij| ≤ |Δ_i| + the largest |Δ|, and d_ij ≥ the boxes' gap, so a pair
// farther apart than that sum over the worst found cannot exceed it).
double segment_distortion(const Configuration& a, const Configuration& b) {
  const std::size_t n = a.size();
  std::vector<double> moved(n);
  double most = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    moved[i] = std::abs(b[i] - a[i]);
    most = std::max(most, moved[i]);
  }
  double worst = 0.0;
  for_each_near_pair(
      swept_boxes(a, b), [&](std::size_t i) { return worst > 0.0 ? (moved[i] + most) / worst : kInf; },
      [&](std::size_t i, std::size_t j) {
        const Point dd = (b[j] - a[j]) - (b[i] - a[i]);
        if (dd == 0.0) return;
        const double d = straight_closest_approach(a[i], b[i] - a[i], a[j], b[j] - a[j]).distance;
        worst = std::max(worst, d > 0.0 ? std::abs(dd) / d : kInf);
      });
  return worst;
}

// Knots in proportion to each segment's mean displacement (every segment moves something).
std::vector<double> knots_for(const std::vector<Configuration>& w) {
  std::vector<double> length(w.size() - 1, 0.0);
  for (std::size_t k = 0; k + 1 < w.size(); ++k) {
    for (std::size_t i = 0; i < w[k].size(); ++i) length[k] += std::abs(w[k + 1][i] - w[k][i]);
    length[k] = length[k] / static_cast<double>(std::max<std::size_t>(1, w[k].size())) + 1e-9;
  }
  const double total = std::accumulate(length.begin(), length.end(), 0.0);
  std::vector<double> knots = {0.0};
  double acc = 0.0;
  for (std::size_t k = 0; k < length.size(); ++k) {
    acc += length[k];
    knots.push_back(k + 1 == length.size() ? 1.0 : acc / total);
  }
  return knots;
}

// A plan with its separation and (for the candidates compared by it) its distortion proxy.
TrajectoryPlan finish(TrajectoryMethod method, std::vector<Configuration> waypoints, std::vector<double> knots,
                      bool with_distortion = true) {
  TrajectoryPlan plan;
  plan.method = method;
  plan.waypoints = std::move(waypoints);
  plan.knots = std::move(knots);
  plan.min_separation_px = plan_min_separation(plan.waypoints);
  if (with_distortion) plan.distortion = plan_distortion(plan.waypoints);
  return plan;
}

// The straight interpolation of sources and targets at time t.
Configuration straight_at(std::span<const Point> s, std::span<const Point> q, double t) {
  Configuration c(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) c[i] = s[i] + t * (q[i] - s[i]);
  return c;
}

// The straight trajectories cut into `segments` equal segments: their waypoints and knots.
void straight_subdivided(std::span<const Point> s, std::span<const Point> q, std::size_t segments,
                         std::vector<Configuration>& w, std::vector<double>& knots) {
  w.clear();
  knots.clear();
  for (std::size_t k = 0; k <= segments; ++k) {
    knots.push_back(k == segments ? 1.0 : static_cast<double>(k) / static_cast<double>(segments));
    w.push_back(k == 0          ? Configuration(s.begin(), s.end())
                : k == segments ? Configuration(q.begin(), q.end())
                                : straight_at(s, q, knots.back()));
  }
}

// Smallest gap between consecutive sorted values.
double min_gap(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  double g = kInf;
  for (std::size_t i = 1; i < v.size(); ++i) g = std::min(g, v[i] - v[i - 1]);
  return g;
}

// v_i + e_i with e non-decreasing in the order of v and consecutive sorted gaps ≥ gap; e centred on mean 0.
std::vector<double> spread(const std::vector<double>& v, double gap) {
  std::vector<std::size_t> order(v.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  std::vector<double> e(v.size(), 0.0);
  for (std::size_t k = 1; k < order.size(); ++k) {
    const double d = v[order[k]] - v[order[k - 1]];
    e[order[k]] = e[order[k - 1]] + std::max(0.0, gap - d);
  }
  const double mean = v.empty() ? 0.0 : std::accumulate(e.begin(), e.end(), 0.0) / static_cast<double>(v.size());
  std::vector<double> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out[i] = v[i] + (e[i] - mean);
  return out;
}

// Moves interior waypoints toward the straight interpolation as far as the separation of their two segments
// stays ≥ keep (bisection on the fraction).
void relax(std::vector<Configuration>& w, const std::vector<double>& knots, std::span<const Point> s,
           std::span<const Point> q, double keep) {
  for (std::size_t k = 1; k + 1 < w.size(); ++k) {
    const Configuration straight = straight_at(s, q, knots[k]);
    const Configuration original = w[k];
    auto at = [&](double lambda) {
      Configuration c(original.size());
      for (std::size_t i = 0; i < c.size(); ++i) c[i] = original[i] + lambda * (straight[i] - original[i]);
      return c;
    };
    auto ok = [&](const Configuration& c) {
      return segment_min_separation(w[k - 1], c) >= keep && segment_min_separation(c, w[k + 1]) >= keep;
    };
    Configuration full = at(1.0);
    if (ok(full)) {
      w[k] = std::move(full);
      continue;
    }
    double lo = 0.0;
    double hi = 1.0;
    for (int step = 0; step < kBisectionSteps; ++step) {
      const double mid = 0.5 * (lo + hi);
      (ok(at(mid)) ? lo : hi) = mid;
    }
    if (lo > 0.0) w[k] = at(lo);
  }
}

// The sweep along direction angle θ (see the file comment), relaxed.
TrajectoryPlan sweep(std::span<const Point> s, std::span<const Point> q, double theta, double gap,
                     double min_separation_px) {
  const std::size_t n = s.size();
  const Point to_rotated = std::polar(1.0, -theta);
  const Point from_rotated = std::polar(1.0, theta);
  std::vector<double> xs(n), ys(n), xt(n), yt(n), mid(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Point a = to_rotated * s[i];
    const Point b = to_rotated * q[i];
    xs[i] = a.real();
    ys[i] = a.imag();
    xt[i] = b.real();
    yt[i] = b.imag();
    mid[i] = 0.5 * (ys[i] + yt[i]);
  }
  const std::vector<double> X = spread(xs, gap);
  const std::vector<double> Xt = spread(xt, gap);
  const std::vector<double> h = spread(mid, gap);
  std::vector<Configuration> all(6, Configuration(n));
  for (std::size_t i = 0; i < n; ++i) {
    all[0][i] = s[i];
    all[1][i] = from_rotated * Point(X[i], ys[i]);
    all[2][i] = from_rotated * Point(X[i], h[i]);
    all[3][i] = from_rotated * Point(Xt[i], h[i]);
    all[4][i] = from_rotated * Point(Xt[i], yt[i]);
    all[5][i] = q[i];
  }
  // Phases without motion (expansions that were not needed) are dropped; by construction they are exact.
  std::vector<Configuration> w = {all[0]};
  if (X != xs) w.push_back(all[1]);
  w.push_back(all[2]);
  w.push_back(all[3]);
  w.push_back(all[4]);
  if (Xt != xt)
    w.push_back(all[5]);
  else
    w.back() = all[5];
  const std::vector<double> knots = knots_for(w);
  const double keep = std::max(min_separation_px, std::min(gap, plan_min_separation(w)));
  relax(w, knots, s, q, keep);
  return finish(TrajectoryMethod::kSweep, std::move(w), knots);
}

// The repair: `inner` intermediate configurations at evenly spaced knots, started on the straight interpolation;
// every pair that passes closer than `target` in a segment is pushed apart at its closest approach (spread over
// the free waypoints at the segment's ends), while all are pulled back toward straight a little. Valid when every
// segment keeps min_separation_px.
TrajectoryPlan repair(std::span<const Point> s, std::span<const Point> q, int inner, double target,
                      double min_separation_px) {
  const std::size_t n = s.size();
  const std::size_t k_count = static_cast<std::size_t>(inner) + 1;
  std::vector<double> knots;
  std::vector<Configuration> w;
  straight_subdivided(s, q, k_count, w, knots);
  std::vector<Configuration> straight = w;
  const double pairs = 0.5 * static_cast<double>(n) * static_cast<double>(n) * static_cast<double>(k_count);
  const int iterations = static_cast<int>(
      std::clamp(kRepairPairBudget / std::max(pairs, 1.0), 20.0, static_cast<double>(kRepairIterations)));
  TrajectoryPlan failed;
  failed.min_separation_px = -kInf;
  for (int it = 0; it < iterations; ++it) {
    if (plan_min_separation(w) >= min_separation_px) return finish(TrajectoryMethod::kRepaired, w, knots);
    std::vector<Configuration> next = w;
    for (std::size_t seg = 0; seg < k_count; ++seg) {
      const double free_a = seg > 0 ? 1.0 : 0.0;
      const double free_b = seg + 1 < k_count ? 1.0 : 0.0;
      // The pairs that may pass closer than `target`, in the order of (i, j) as an all-pairs loop would take them.
      std::vector<std::pair<std::size_t, std::size_t>> near;
      for_each_near_pair(
          swept_boxes(w[seg], w[seg + 1]), [&](std::size_t) { return target; },
          [&](std::size_t i, std::size_t j) { near.emplace_back(i, j); });
      std::sort(near.begin(), near.end());
      for (const auto& [i, j] : near) {
        {
          const Point di = w[seg + 1][i] - w[seg][i];
          const Point dj = w[seg + 1][j] - w[seg][j];
          const auto [tau, d] = straight_closest_approach(w[seg][i], di, w[seg][j], dj);
          if (d >= target) continue;
          Point r = (w[seg][j] + tau * dj) - (w[seg][i] + tau * di);
          Point u;
          if (std::abs(r) > 1e-9 * target) {
            u = r / std::abs(r);
          } else {  // they meet: push across their relative motion, the way that depends on the pair only
            const Point rel = dj - di;
            u = std::abs(rel) > 0.0 ? Point(0.0, 1.0) * rel / std::abs(rel) : Point(1.0, 0.0);
          }
          const double wa = free_a * (1.0 - tau);
          const double wb = free_b * tau;
          const double norm = wa * wa + wb * wb;
          if (norm < 1e-6) continue;
          const Point push = 0.5 * (target - d) * u / norm;
          if (wa > 0.0) {
            next[seg][i] -= wa * push;
            next[seg][j] += wa * push;
          }
          if (wb > 0.0) {
            next[seg + 1][i] -= wb * push;
            next[seg + 1][j] += wb * push;
          }
        }
      }
    }
    for (std::size_t k = 1; k < k_count; ++k) {
      for (std::size_t i = 0; i < n; ++i) next[k][i] += 0.02 * (straight[k][i] - next[k][i]);
    }
    w = std::move(next);
  }
  if (plan_min_separation(w) >= min_separation_px) return finish(TrajectoryMethod::kRepaired, w, knots);
  return failed;
}

// The pair energy of one segment: ∫_0^1 |c_ij(s)|² ds for a pair whose offset ΔF = F_j − F_i moves straight from
// a to b (c_ij = ΔD/ΔF, Eq. 2), in closed form: |b − a|²·φ / (|a|·|b|·sin φ), φ the angle between a and b. With
// its gradients in a and b (as 2-vectors in complex form).
struct PairEnergy {
  double value = 0.0;
  double factor = 0.0;  // f = φ / (|a|·|b|·sin φ): value = |b − a|²·f
  Point d_a = 0.0;
  Point d_b = 0.0;
};

PairEnergy pair_energy(Point a, Point b) {
  PairEnergy e;
  const double na = std::norm(a);
  const double nb = std::norm(b);
  if (na == 0.0 || nb == 0.0) {
    e.value = kInf;
    return e;
  }
  const double psi = std::arg(b / a);  // signed angle from a to b
  const double phi = std::abs(psi);
  if (phi >= std::numbers::pi * (1.0 - 1e-12)) {
    e.value = kInf;
    return e;
  }
  // ψ/sin ψ and k(ψ) = d ln(ψ/sin ψ)/dψ = 1/ψ − cot ψ, by series near 0.
  const double psi2 = psi * psi;
  const double ratio = phi < 1e-4 ? 1.0 + psi2 / 6.0 : phi / std::sin(phi);
  const double k = phi < 1e-4 ? psi / 3.0 + psi * psi2 / 45.0 : 1.0 / psi - 1.0 / std::tan(psi);
  const double f = ratio / std::sqrt(na * nb);
  e.factor = f;
  const Point delta = b - a;
  const double dd = std::norm(delta);
  e.value = dd * f;
  const Point i(0.0, 1.0);
  // ∇ ln f: −a/|a|² − k·i·a/|a|² in a; −b/|b|² + k·i·b/|b|² in b.
  e.d_a = -2.0 * delta * f + e.value * (-(a + k * i * a) / na);
  e.d_b = 2.0 * delta * f + e.value * (-(b - k * i * b) / nb);
  return e;
}

// The gradient of the plan's energy in every waypoint, each point's curvature proxy (the scale of the energy's second
// derivative in that point: Σ over its pairs of 2f, the Hessian of |b − a|²·f with f held, plus the pair's energy over
// its squared distance at that end, the scale of f's own), and the pairs visited.
struct EnergyTerms {
  std::vector<Configuration> gradient;
  std::vector<std::vector<double>> curvature;
  std::size_t pairs = 0;
};

// The plan's energy: Σ over segments k and pairs whose swept boxes come within `reach` of ∫|c_ij|² dt in the plan's
// time (a segment of duration τ weighs 1/τ); with `terms`, its gradient and curvature proxy too.
double plan_energy_terms(const std::vector<Configuration>& w, const std::vector<double>& knots, double reach,
                         EnergyTerms* terms) {
  if (terms != nullptr) {
    terms->gradient.assign(w.size(), Configuration(w.front().size(), Point(0.0)));
    terms->curvature.assign(w.size(), std::vector<double>(w.front().size(), 0.0));
    terms->pairs = 0;
  }
  double total = 0.0;
  for (std::size_t k = 0; k + 1 < w.size(); ++k) {
    const double inv_tau = 1.0 / (knots[k + 1] - knots[k]);
    for_each_near_pair(
        swept_boxes(w[k], w[k + 1]), [&](std::size_t) { return reach; },
        [&](std::size_t i, std::size_t j) {
          const Point a = w[k][j] - w[k][i];
          const Point b = w[k + 1][j] - w[k + 1][i];
          const PairEnergy e = pair_energy(a, b);
          total += inv_tau * e.value;
          if (terms == nullptr) return;
          ++terms->pairs;
          terms->gradient[k][j] += inv_tau * e.d_a;
          terms->gradient[k][i] -= inv_tau * e.d_a;
          terms->gradient[k + 1][j] += inv_tau * e.d_b;
          terms->gradient[k + 1][i] -= inv_tau * e.d_b;
          const double ca = inv_tau * (2.0 * e.factor + e.value / std::norm(a));
          const double cb = inv_tau * (2.0 * e.factor + e.value / std::norm(b));
          terms->curvature[k][i] += ca;
          terms->curvature[k][j] += ca;
          terms->curvature[k + 1][i] += cb;
          terms->curvature[k + 1][j] += cb;
        });
  }
  return total;
}

// Lowers the plan's energy (see the file comment): Jacobi-preconditioned descent on the interior waypoints (each
// point's step its gradient over its pairs' curvature proxy, at most a quarter of the length scale), a step accepted
// only where the energy falls and the separation keeps `keep`. A one-segment plan first gets kEnergySegments − 1
// interior waypoints on its straight lines. Knots stay. Bounded by kEnergyIterations and kEnergyPairBudget pair
// evaluations.
TrajectoryPlan lower_plan_energy(const TrajectoryPlan& plan, double keep, double length_px) {
  std::vector<Configuration> w = plan.waypoints;
  std::vector<double> knots = plan.knots;
  if (w.size() == 2) straight_subdivided(plan.waypoints.front(), plan.waypoints.back(), kEnergySegments, w, knots);
  const double reach = kEnergyReach * length_px;
  const double max_step = 0.25 * length_px;
  EnergyTerms terms;
  double energy = plan_energy_terms(w, knots, reach, &terms);
  const double before = energy;
  auto evaluations = static_cast<double>(terms.pairs);
  double step = 1.0;
  for (int it = 0; it < kEnergyIterations && step > 1e-6 && evaluations < kEnergyPairBudget; ++it) {
    std::vector<Configuration> trial = w;
    double moved = 0.0;
    for (std::size_t k = 1; k + 1 < w.size(); ++k) {
      for (std::size_t i = 0; i < w[k].size(); ++i) {
        Point d = step * terms.gradient[k][i] / (terms.curvature[k][i] + 1e-300);
        if (std::abs(d) > max_step) d *= max_step / std::abs(d);
        trial[k][i] -= d;
        moved = std::max(moved, std::abs(d));
      }
    }
    if (moved < 1e-4 * length_px) break;
    EnergyTerms trial_terms;
    const double e = plan_energy_terms(trial, knots, reach, &trial_terms);
    evaluations += static_cast<double>(trial_terms.pairs);
    if (e < energy && plan_min_separation(trial) >= keep) {
      w = std::move(trial);
      terms = std::move(trial_terms);
      energy = e;
      step = std::min(1.0, 1.5 * step);
    } else {
      step *= 0.5;
    }
  }
  if (!(energy < before)) {
    TrajectoryPlan same = plan;
    same.energy_before = before;
    same.energy = before;
    same.energy_measured = true;
    return same;
  }
  TrajectoryPlan lowered =
      finish(plan.method == TrajectoryMethod::kStraight ? TrajectoryMethod::kRepaired : plan.method, std::move(w),
             std::move(knots));
  lowered.energy = energy;
  lowered.energy_before = before;
  lowered.energy_measured = true;
  return lowered;
}

}  // namespace

double plan_min_separation(const std::vector<std::vector<Point>>& waypoints) {
  double best = kInf;
  for (std::size_t k = 0; k + 1 < waypoints.size(); ++k) {
    best = std::min(best, segment_min_separation(waypoints[k], waypoints[k + 1]));
  }
  return best;
}

double plan_energy(const std::vector<std::vector<Point>>& waypoints, const std::vector<double>& knots, double reach_px,
                   std::vector<std::vector<Point>>* gradient) {
  if (waypoints.empty()) {
    if (gradient != nullptr) gradient->clear();
    return 0.0;
  }
  if (gradient == nullptr) return plan_energy_terms(waypoints, knots, reach_px, nullptr);
  EnergyTerms terms;
  const double energy = plan_energy_terms(waypoints, knots, reach_px, &terms);
  *gradient = std::move(terms.gradient);
  return energy;
}

double plan_distortion(const std::vector<std::vector<Point>>& waypoints) {
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < waypoints.size(); ++k) sum += segment_distortion(waypoints[k], waypoints[k + 1]);
  return sum;
}

TrajectoryPlan plan_trajectories(std::span<const Point> sources, std::span<const Point> targets,
                                 double min_separation_px, double length_px, bool lower_energy,
                                 bool widen_near_misses) {
  const std::size_t n = sources.size();
  // 1. Straight: today's trajectories whenever they keep the separation.
  TrajectoryPlan straight =
      finish(TrajectoryMethod::kStraight,
             {Configuration(sources.begin(), sources.end()), Configuration(targets.begin(), targets.end())}, {0.0, 1.0},
             false);  // the straight plan's cost is that of the collision check before planning
  if (n < 2) return straight;
  if (straight.min_separation_px >= min_separation_px) {
    return lower_energy ? lower_trajectory_energy(straight, min_separation_px, length_px, widen_near_misses) : straight;
  }

  // Extent of the set: the sweep's gaps are a share of it, so that the sweep stays about the set's size.
  double extent = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    extent = std::max({extent, std::abs(sources[i] - sources[0]), std::abs(targets[i] - targets[0])});
  }
  const double gap =
      std::max(2.0 * min_separation_px, std::min(0.5 * length_px, extent / (2.0 * static_cast<double>(n))));

  std::vector<TrajectoryPlan> candidates;
  // 2. Repairs: one and three intermediate configurations.
  for (const int inner : {1, 3}) {
    TrajectoryPlan r = repair(sources, targets, inner, gap, min_separation_px);
    if (r.min_separation_px >= min_separation_px) candidates.push_back(std::move(r));
  }
  // 3. Sweeps along the directions where the projections of sources and of targets are best spread.
  std::vector<std::pair<double, double>> directions;  // (−spread, θ)
  for (int a = 0; a < kSweepDirections; ++a) {
    const double theta = std::numbers::pi * a / kSweepDirections;
    const Point r = std::polar(1.0, -theta);
    std::vector<double> xs(n), xt(n);
    for (std::size_t i = 0; i < n; ++i) {
      xs[i] = (r * sources[i]).real();
      xt[i] = (r * targets[i]).real();
    }
    directions.emplace_back(-std::min(min_gap(xs), min_gap(xt)), theta);
  }
  std::sort(directions.begin(), directions.end());
  TrajectoryPlan best_sweep;
  best_sweep.min_separation_px = -kInf;
  for (int c = 0; c < kSweepCandidates; ++c) {
    TrajectoryPlan p = sweep(sources, targets, directions[c].second, gap, min_separation_px);
    if (p.min_separation_px >= min_separation_px) {
      candidates.push_back(std::move(p));
    } else if (p.min_separation_px > best_sweep.min_separation_px) {
      best_sweep = std::move(p);  // sources or targets themselves too close: the best there is
    }
  }
  if (candidates.empty()) {
    best_sweep.straight_collides = true;
    return best_sweep;
  }
  TrajectoryPlan chosen =
      *std::min_element(candidates.begin(), candidates.end(),
                        [](const TrajectoryPlan& a, const TrajectoryPlan& b) { return a.distortion < b.distortion; });
  chosen.straight_collides = true;
  return lower_energy ? lower_trajectory_energy(chosen, min_separation_px, length_px, widen_near_misses) : chosen;
}

TrajectoryPlan lower_trajectory_energy(const TrajectoryPlan& plan, double min_separation_px, double length_px,
                                       bool widen_near_misses) {
  if (plan.waypoints.empty() || plan.waypoints.front().size() < 2) return plan;
  if (plan.min_separation_px < min_separation_px) return plan;  // no plan keeps the minimum: nothing to keep
  if (!plan.straight_collides) {
    // Straight lines that keep the minimum: lowered only when asked and a pair passes closer than kEnergyNearMiss.
    const bool near_miss = plan.min_separation_px < kEnergyNearMiss * length_px;
    if (!(widen_near_misses && near_miss && plan.segments() == 1)) return plan;
  }
  TrajectoryPlan lowered = lower_plan_energy(plan, min_separation_px, length_px);
  lowered.straight_collides = plan.straight_collides;
  return lowered;
}

}  // namespace texwarp
