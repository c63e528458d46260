// A warp problem's sections of the typed report (proto/job_report.hpp): its set-up, pre-alignment, closest
// approach and trajectories, and Jacobian-determinant statistics; shared by the job runner, `texwarp check` and the
// mesh report.
#pragma once

#include <optional>

#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/proto/job_report.hpp"

namespace texwarp {

// alpha, pre-alignment, pathline tolerance, and the problem's features (of which gradient features).
proto::WarpSetupReport warp_setup_report(const WarpProblem& problem);

// S of Section 3.3: scale, angle in degrees, translation in pixels.
proto::PrealignmentReport prealignment_report(const Similarity& prealignment);

// The pair of features whose trajectories come closest; nullopt when there is no pair (fewer than two).
std::optional<proto::ClosestApproachReport> closest_approach_report(const WarpProblem& problem);

// The planned trajectories: segments, method, knots, the separation kept; with `waypoints`, the waypoints too.
proto::TrajectoryReport trajectory_report(const WarpProblem& problem, bool waypoints = false);

proto::JacobianReport jacobian_report(const JacobianStats& stats, proto::JacobianEstimate map, int step_px);

}  // namespace texwarp
