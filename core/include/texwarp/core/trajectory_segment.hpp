// TrajectorySegment: one straight stretch of every feature's trajectory, between two knots of the plan, on its own
// local unit time: the features' straight motions, the gradient rates of that stretch, the collision facts found
// for it (closest approach, near-collisions) and the weights' length unit. The warp is the composition of them.
#pragma once

#include <cstddef>
#include <limits>
#include <span>
#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp {

// A positional feature's trajectory over a segment (local time t ∈ [0, 1]): F(t) = start + t·velocity.
struct PositionalTrajectory {
  Point start;
  Point velocity;       // D = end − start of the segment (for one segment: Q − S(P))
  std::size_t feature;  // index into the input features
};

// A gradient feature's trajectory and its similarity rate κ = ln(S) + i·φ (Eq. 4 in complex form): the field
// it contributes is v_g(p) = D + κ·(p − F(t)); its Jacobian at t = 1 is e^κ relative to the pre-aligned frame.
// Over a segment of duration Δt, κ is the whole rate times Δt (the segments' rates add up to the whole).
struct GradientTrajectory {
  Point start;
  Point velocity;
  Point rate;  // κ
  std::size_t feature;
};

// The closest approach of any two features' trajectories (after pre-alignment): what the collision check saw.
struct ClosestApproach {
  std::size_t first = 0;  // feature indices, first < second
  std::size_t second = 0;
  double t = 0.0;            // global time in [0, 1] (the knots map a segment's local time to it)
  double distance_px = 0.0;  // +inf with fewer than two features
};

// A near-collision of two feature trajectories (positional or gradient, after pre-alignment): they pass closest
// at local time t ∈ (0, 1) of their segment, distance d apart with relative speed s. The field around them (c_ij(t)
// of the pair, and the weights) changes within about τ = d / s of t, a window an adaptive step can jump over
// without its error estimate noticing; integrate_pathlines keeps its steps from doing so (pathline.cpp).
struct NearCollision {
  double t = 0.0;
  double width = 0.0;  // kNearCollisionWidthFactor·τ, unit time
};

// Passes with τ below kNearCollisionMaxTau are near-collisions (wider ones the step control resolves by
// itself); their window is kNearCollisionWidthFactor·τ. Both backends cap their steps with them.
inline constexpr double kNearCollisionMaxTau = 0.05;
inline constexpr double kNearCollisionWidthFactor = 4.0;

// Closest approach of two straight trajectories x(t) = x0 + t·dx, y(t) = y0 + t·dy over t ∈ [0, 1]:
// {t*, distance}, exact.
struct PairApproach {
  double t = 0.0;
  double distance = 0.0;
};
PairApproach straight_closest_approach(Point x0, Point dx, Point y0, Point dy);

struct TrajectorySegment {
  std::vector<PositionalTrajectory> positional;
  std::vector<GradientTrajectory> gradient;
  bool field_is_zero = true;      // no constraint moves in this segment: its warp is the identity
  double weight_length_px = 1.0;  // the weights' length unit over this segment (WarpProblem::weight_length_px)
  ClosestApproach closest;        // t in global time
  std::vector<NearCollision> near_collisions;  // by local time
  // The shortest time within which the field can change (local time): over every pair of features their closest
  // distance over their relative speed (the pair's τ above, wherever they pass), and a gradient feature's
  // 1 / |rate|; +inf where nothing moves relative to anything. The first step of a pathline follows it
  // (dormand_prince::first_step).
  double time_scale = std::numeric_limits<double>::infinity();
};

// The segment in which every feature i moves straight from `from[i]` to `to[i]` over global time
// [t_begin, t_end]: `rates[i]` is the whole warp's gradient rate κ of feature i (used when `gradient[i]`), split in
// proportion to the segment's duration. `weight_length_px` is the segment's unit (see WarpProblem).
TrajectorySegment make_segment(std::span<const Point> from, std::span<const Point> to, std::span<const Point> rates,
                               const std::vector<bool>& gradient, double t_begin, double t_end,
                               double weight_length_px);

// The median over features of the distance to the nearest other feature, averaged over the two configurations
// (a segment's ends); 1 with fewer than two features.
double median_nearest_distance(std::span<const Point> from, std::span<const Point> to);

}  // namespace texwarp
