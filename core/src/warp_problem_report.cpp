// A warp problem's sections of the typed report: see warp_problem_report.hpp.
#include "texwarp/core/warp_problem_report.hpp"

#include <cmath>
#include <numbers>

namespace texwarp {

proto::WarpSetupReport warp_setup_report(const WarpProblem& problem) {
  proto::WarpSetupReport r;
  r.alpha = problem.alpha();
  r.prealign = problem.options().prealign;
  r.tolerance_px = problem.tolerance_px();
  r.features = problem.size();
  for (const Feature& f : problem.features()) r.gradient_features += f.is_gradient() ? 1 : 0;
  return r;
}

proto::PrealignmentReport prealignment_report(const Similarity& prealignment) {
  return {prealignment.scale(),
          prealignment.angle_rad() * 180.0 / std::numbers::pi,
          {prealignment.b.real(), prealignment.b.imag()}};
}

std::optional<proto::ClosestApproachReport> closest_approach_report(const WarpProblem& problem) {
  const ClosestApproach& ca = problem.closest_approach();
  if (!std::isfinite(ca.distance_px)) return std::nullopt;
  return proto::ClosestApproachReport{
      {describe_feature(problem.features(), ca.first), describe_feature(problem.features(), ca.second)},
      ca.t,
      ca.distance_px};
}

proto::TrajectoryReport trajectory_report(const WarpProblem& problem, bool waypoints) {
  const TrajectoryPlan& plan = problem.trajectory_plan();
  proto::TrajectoryReport r;
  r.segments = plan.segments();
  r.method = plan.method;
  if (std::isfinite(plan.min_separation_px)) r.min_separation_px = plan.min_separation_px;
  r.knots = plan.knots;
  if (plan.energy_measured) {
    r.energy_before = plan.energy_before;
    r.energy = plan.energy;
  }
  if (waypoints) {
    auto& out = r.waypoints.emplace();
    for (const auto& configuration : plan.waypoints) {
      auto& row = out.emplace_back();
      for (const Point& p : configuration) row.push_back({p.real(), p.imag()});
    }
  }
  return r;
}

proto::JacobianReport jacobian_report(const JacobianStats& stats, proto::JacobianEstimate map, int step_px) {
  proto::JacobianReport r;
  r.map = map;
  r.step_px = step_px;
  r.samples = stats.samples;
  r.min_det = stats.min_det;
  r.max_det = stats.max_det;
  r.nonpositive = stats.nonpositive;
  return r;
}

}  // namespace texwarp
