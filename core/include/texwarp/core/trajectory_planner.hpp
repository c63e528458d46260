// The trajectory planner: piecewise linear trajectories, through waypoints shared by all features, that keep every
// two features at least a minimum distance apart (exact closest approach per segment and pair). Straight lines when
// they do; else a cheap repair (intermediate configurations pushed apart); else a sweep, collision-free by
// construction for any distinct sources and distinct targets. Pure: points in, plan out (DESIGN.md §1).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/proto/trajectory_method.hpp"

namespace texwarp {

using proto::TrajectoryMethod;

struct TrajectoryPlan {
  TrajectoryMethod method = TrajectoryMethod::kStraight;
  // K + 1 configurations: waypoints[k][i] is feature i at knots[k]; waypoints[0] the (pre-aligned) sources,
  // waypoints[K] the targets. Between knots every feature moves straight.
  std::vector<std::vector<Point>> waypoints;
  std::vector<double> knots;       // 0 = t_0 < … < t_K = 1
  double min_separation_px = 0.0;  // exact minimum over segments and pairs; +inf with fewer than two features
  double distortion = 0.0;  // the planner's proxy: Σ over segments of max over pairs of |ΔD_ij| / d_ij (see .cpp)
  // The pair energy (plan_energy at 4 length scales) where lowering it was tried (energy_measured): before and after.
  double energy_before = 0.0;
  double energy = 0.0;
  bool energy_measured = false;
  bool straight_collides = false;  // the straight trajectories come closer than the minimum (they were not kept)
  std::size_t segments() const { return knots.empty() ? 0 : knots.size() - 1; }
  // Whether the waypoints were moved to lower it (a plan is kept as found unless its energy fell).
  bool energy_lowered() const { return energy_measured && energy < energy_before; }
};

// The exact minimum distance between any two features over a plan's segments (+inf with fewer than two).
double plan_min_separation(const std::vector<std::vector<Point>>& waypoints);

// The planner's distortion proxy of a plan (see trajectory_planner.cpp).
double plan_distortion(const std::vector<std::vector<Point>>& waypoints);

// The plan's pair energy: Σ over segments and over the pairs whose swept boxes come within `reach_px` of each other
// of ∫ |c_ij(t)|² dt over the segment's time (knots), c_ij = ΔD_ij / ΔF_ij(t) the rate at which the pair's field
// (Eq. 2–3) scales and turns; ∞ when a pair meets. With `gradient`, also its gradient in every waypoint (as 2-vectors
// in complex form: ∂E/∂x + i·∂E/∂y), summed over the same pairs.
double plan_energy(const std::vector<std::vector<Point>>& waypoints, const std::vector<double>& knots, double reach_px,
                   std::vector<std::vector<Point>>* gradient = nullptr);

// Plans trajectories from `sources` (pre-aligned) to `targets` keeping `min_separation_px`. `length_px` is the
// features' length scale (their median nearest spacing): the gaps the sweep opens. With `lower_energy`, a plan with
// intermediate configurations then has them moved to lower its pair energy, keeping the minimum; with
// `widen_near_misses`, so do straight lines whose pairs pass closer than a quarter of the length scale (given
// intermediate configurations first). Returns a plan whose min_separation_px is below the minimum only when no plan
// can keep it (sources or targets themselves closer).
TrajectoryPlan plan_trajectories(std::span<const Point> sources, std::span<const Point> targets,
                                 double min_separation_px, double length_px, bool lower_energy = true,
                                 bool widen_near_misses = false);

// The lowering step of plan_trajectories on a plan it made with `lower_energy` false: what it would have returned with
// it true (the same plan where nothing is lowered). For callers that may plan again before keeping a plan.
TrajectoryPlan lower_trajectory_energy(const TrajectoryPlan& plan, double min_separation_px, double length_px,
                                       bool widen_near_misses);

}  // namespace texwarp
