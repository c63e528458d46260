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
  for (std::size_t k = 0; k <= k_count; ++k) {
    knots.push_back(k == k_count ? 1.0 : static_cast<double>(k) / static_cast<double>(k_count));
    w.push_back(k == 0         ? Configuration(s.begin(), s.end())
                : k == k_count ? Configuration(q.begin(), q.end())
                               : straight_at(s, q, knots.back()));
  }
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

}  // namespace

double plan_min_separation(const std::vector<std::vector<Point>>& waypoints) {
  double best = kInf;
  for (std::size_t k = 0; k + 1 < waypoints.size(); ++k) {
    best = std::min(best, segment_min_separation(waypoints[k], waypoints[k + 1]));
  }
  return best;
}

double plan_distortion(const std::vector<std::vector<Point>>& waypoints) {
  double sum = 0.0;
  for (std::size_t k = 0; k + 1 < waypoints.size(); ++k) sum += segment_distortion(waypoints[k], waypoints[k + 1]);
  return sum;
}

TrajectoryPlan plan_trajectories(std::span<const Point> sources, std::span<const Point> targets,
                                 double min_separation_px, double length_px) {
  const std::size_t n = sources.size();
  // 1. Straight: today's trajectories whenever they keep the separation.
  TrajectoryPlan straight =
      finish(TrajectoryMethod::kStraight,
             {Configuration(sources.begin(), sources.end()), Configuration(targets.begin(), targets.end())}, {0.0, 1.0},
             false);  // the straight plan's cost is that of the collision check before planning
  if (n < 2 || straight.min_separation_px >= min_separation_px) return straight;

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
  if (candidates.empty()) return best_sweep;
  return *std::min_element(candidates.begin(), candidates.end(), [](const TrajectoryPlan& a, const TrajectoryPlan& b) {
    return a.distortion < b.distortion;
  });
}

}  // namespace texwarp
