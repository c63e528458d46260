// WarpProblem: validated features turned into the moving constraints of the vector field (DESIGN.md §1):
// pre-alignment S, planned trajectories (K straight segments through shared waypoints), gradient rates κ = ln S + iφ.
// The whole map is f = W_{K−1} ∘ … ∘ W_0 ∘ S, W_k the time-1 flow of segment k's field; f⁻¹ = S⁻¹ ∘ W_0⁻¹ ∘ … .
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "texwarp/core/direction.hpp"
#include "texwarp/core/feature.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/similarity.hpp"
#include "texwarp/core/trajectory_planner.hpp"
#include "texwarp/core/trajectory_segment.hpp"
#include "texwarp/core/warp_options.hpp"

namespace texwarp {

struct FlowGrowthCache;  // flow_growth.hpp

// A pre-alignment that shrinks more than this is relaxed to it when the trajectories need planning (see build()).
inline constexpr double kMinPlannedPrealignScale = 0.5;

class WarpProblem {
 public:
  // Validates (InputError naming the feature or option on failure) and prepares. Checks: finite numbers,
  // alpha ∈ (0, kMaxAlpha], tolerance > 0, frames with positive scale, duplicate sources or targets. Then plans
  // the trajectories (trajectory_planner.hpp) so that no two features come closer than min_separation_px: only
  // sources or targets themselves closer than that are refused.
  WarpProblem(std::vector<Feature> features, WarpOptions options);

  // The same problem integrated to another tolerance: nothing but tolerance_px depends on it, so the pre-alignment,
  // trajectories and segments are copied, not planned again. InputError ($.tolerance_px) as the constructor's.
  WarpProblem with_tolerance(double tolerance_px) const;

  const std::vector<Feature>& features() const { return features_; }
  const WarpOptions& options() const { return options_; }
  double alpha() const { return options_.alpha; }
  double tolerance_px() const { return options_.tolerance_px; }

  // The tolerance each pathline is integrated to, in the flow's own (pre-aligned) space, so that the points a map
  // returns meet tolerance_px where they land. An inverse map's points leave the flow through S⁻¹, which multiplies
  // their errors by 1/|a| (a the pre-alignment's scale): its pathlines meet |a|·tolerance_px where |a| < 1. A forward
  // map's points leave the flow as they are. With K > 1 segments it is also scaled by the flow's growth scale once
  // measured (flow_growth.hpp): an error made in one segment grows through the later ones. Every backend integrates
  // to this.
  double pathline_tolerance_px(Direction direction) const;

  // The growth scale of `direction`'s maps (≤ 1; 1 until measured by ensure_growth_scale, and for K = 1), and where
  // it is kept: shared with the problem's copies.
  double growth_scale(Direction direction) const;
  FlowGrowthCache& growth_cache() const { return *growth_; }

  const Similarity& prealignment() const { return prealignment_; }

  // The K ≥ 1 segments, in time order, and the plan they come from (waypoints, knots, method, separation).
  const std::vector<TrajectorySegment>& segments() const { return segments_; }
  const TrajectoryPlan& trajectory_plan() const { return plan_; }

  // Segment 0's trajectories, near-collisions and weight unit: with straight trajectories (K = 1), the whole
  // warp's. Code that runs the warp goes through segments().
  const std::vector<PositionalTrajectory>& positional() const { return segments_.front().positional; }
  const std::vector<GradientTrajectory>& gradient() const { return segments_.front().gradient; }
  const std::vector<NearCollision>& near_collisions() const { return segments_.front().near_collisions; }

  // True when the field is zero everywhere in every segment (W is the identity): no constraint moves.
  bool field_is_zero() const { return field_is_zero_; }

  std::size_t size() const { return features_.size(); }

  // The closest approach over all segments (t in global time).
  const ClosestApproach& closest_approach() const { return closest_; }

  // Length unit of the weights d^−α (pixels): the median over features of the distance to the nearest other
  // feature (mean of that distance at the segment's two ends, after pre-alignment); 1 with fewer than two
  // features. Pair weights scale as length^−2α and gradient weights as length^−α, so the unit sets how far a
  // gradient feature reaches before the pairs take over: about d_i·d_j / unit for neighbours at d_i, d_j, i.e. out
  // to its neighbours. In raw pixels a gradient feature would instead outweigh every pair beyond a few pixels, and
  // with the image's size as the unit it would act within a pixel only. A unit taken from the features also
  // makes the warp independent of resolution (the same features, scaled, give the same warp, scaled).
  // This is segment 0's; each segment has its own (TrajectorySegment::weight_length_px).
  double weight_length_px() const { return segments_.front().weight_length_px; }

 private:
  static void validate_tolerance(double tolerance_px);
  void validate() const;
  void build();

  std::vector<Feature> features_;
  WarpOptions options_;
  Similarity prealignment_;
  TrajectoryPlan plan_;
  std::vector<TrajectorySegment> segments_;
  bool field_is_zero_ = true;
  ClosestApproach closest_;
  std::shared_ptr<FlowGrowthCache> growth_;
};

}  // namespace texwarp
