// WarpProblem: validated features turned into the moving constraints of the vector field (DESIGN.md §1):
// pre-alignment S, straight feature trajectories F(t) = start + t·velocity, gradient rates κ = ln S + iφ.
// The whole map is f = W ∘ S, W the time-1 flow of the field; f⁻¹ = S⁻¹ ∘ W⁻¹.
#pragma once

#include <cstddef>
#include <vector>

#include "texwarp/core/feature.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/similarity.hpp"
#include "texwarp/core/warp_options.hpp"

namespace texwarp {

// A positional feature's trajectory after pre-alignment: F(t) = start + t·velocity, t ∈ [0, 1].
struct PositionalTrajectory {
  Point start;
  Point velocity;       // D = Q − S(P)
  std::size_t feature;  // index into the input features
};

// A gradient feature's trajectory and its similarity rate κ = ln(S) + i·φ (Eq. 4 in complex form): the field
// it contributes is v_g(p) = D + κ·(p − F(t)); its Jacobian at t = 1 is e^κ relative to the pre-aligned frame.
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
  double t = 0.0;
  double distance_px = 0.0;  // +inf with fewer than two features
};

// A near-collision of two feature trajectories (positional or gradient, after pre-alignment): they pass closest
// at t ∈ (0, 1), distance d apart with relative speed s. The field around them (c_ij(t) of the pair, and the
// weights) changes within about τ = d / s of t, a window an adaptive step can jump over without its error
// estimate noticing; integrate_pathlines keeps its steps from doing so (pathline.cpp).
struct NearCollision {
  double t = 0.0;
  double width = 0.0;  // kNearCollisionWidthFactor·τ, unit time
};

// Passes with τ below kNearCollisionMaxTau are near-collisions (wider ones the step control resolves by
// itself); their window is kNearCollisionWidthFactor·τ. Both backends cap their steps with them.
inline constexpr double kNearCollisionMaxTau = 0.05;
inline constexpr double kNearCollisionWidthFactor = 4.0;

class WarpProblem {
 public:
  // Validates (InputError naming the feature or option on failure) and prepares. Checks: finite numbers,
  // alpha ∈ (0, kMaxAlpha], tolerance > 0, frames with positive scale, duplicate sources or targets, and
  // collisions of the straight trajectories after pre-alignment (exact closest approach per pair).
  WarpProblem(std::vector<Feature> features, WarpOptions options);

  const std::vector<Feature>& features() const { return features_; }
  const WarpOptions& options() const { return options_; }
  double alpha() const { return options_.alpha; }
  double tolerance_px() const { return options_.tolerance_px; }

  const Similarity& prealignment() const { return prealignment_; }
  const std::vector<PositionalTrajectory>& positional() const { return positional_; }
  const std::vector<GradientTrajectory>& gradient() const { return gradient_; }

  // True when the field is zero everywhere (W is the identity): no constraint moves.
  bool field_is_zero() const { return field_is_zero_; }

  std::size_t size() const { return features_.size(); }

  const ClosestApproach& closest_approach() const { return closest_; }

  // Every near-collision of two trajectories, by time: found with the collision check (O(n²), once).
  const std::vector<NearCollision>& near_collisions() const { return near_collisions_; }

  // Length unit of the weights d^−α (pixels): the median over features of the distance to the nearest other
  // feature (mean of that distance at t = 0 and t = 1, after pre-alignment); 1 with fewer than two features.
  // Pair weights scale as length^−2α and gradient weights as length^−α, so the unit sets how far a gradient
  // feature reaches before the pairs take over: about d_i·d_j / unit for neighbours at d_i, d_j, i.e. out to
  // its neighbours. In raw pixels a gradient feature would instead outweigh every pair beyond a few pixels, and
  // with the image's size as the unit it would act within a pixel only. A unit taken from the features also
  // makes the warp independent of resolution (the same features, scaled, give the same warp, scaled).
  double weight_length_px() const { return weight_length_px_; }

 private:
  void validate() const;
  void build();
  void check_collisions();

  std::vector<Feature> features_;
  WarpOptions options_;
  Similarity prealignment_;
  std::vector<PositionalTrajectory> positional_;
  std::vector<GradientTrajectory> gradient_;
  bool field_is_zero_ = true;
  ClosestApproach closest_;
  std::vector<NearCollision> near_collisions_;
  double weight_length_px_ = 1.0;
};

}  // namespace texwarp
