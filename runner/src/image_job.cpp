// Running an image job's plan: warp the texture, measure the constraint residuals (and on request the Jacobian
// over the output), write the warped image and the report.
#include "job_runs.hpp"

#include <algorithm>
#include <optional>

#include "texwarp/core/atomic_file.hpp"

#include "job_steps.hpp"
#include "texwarp/core/closed_form_warp.hpp"
#include "texwarp/core/constraint_residuals.hpp"
#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/warp_problem_report.hpp"
#include "texwarp/runner/stage_costs.hpp"

namespace texwarp::runner {
namespace {

constexpr int kJacobianMaxGridSide = 64;  // jacobian_check: at most this many grid nodes per side

// |f(P_i) − Q_i| per feature, measured with the backend (constraint_residuals.hpp).
proto::ResidualsReport residuals_report(WarpBackend& backend, const WarpProblem& problem, const RunControl& control) {
  const ConstraintResiduals residuals = constraint_residuals(backend, problem, control);
  proto::ResidualsReport r;
  r.max_px = residuals.max;
  for (std::size_t i = 0; i < residuals.per_feature.size(); ++i) {
    r.per_feature.push_back(
        {describe_feature(problem.features(), i), problem.features()[i].id, residuals.per_feature[i]});
  }
  return r;
}

// Determinants of the inverse map's Jacobian at output pixel centres, on a grid of at most 64 nodes per side.
proto::JacobianReport output_jacobian(WarpBackend& backend, const WarpProblem& problem, int width, int height,
                                      const RunControl& control) {
  const int step = std::max(1, (std::max(width, height) + kJacobianMaxGridSide - 1) / kJacobianMaxGridSide);
  std::vector<Point> grid;
  for (int y = 0; y < height; y += step) {
    for (int x = 0; x < width; x += step) grid.emplace_back(x + 0.5, y + 0.5);
  }
  const JacobianStats stats =
      summarize_determinants(warp_jacobian_determinants(backend, problem, grid, Direction::kInverse, control));
  return jacobian_report(stats, proto::JacobianEstimate::kVariationalEquation, step);
}

// The warp's sections; the maps' are added as they are written.
proto::ImageJobReport image_sections(const JobPlan& plan) {
  const proto::JobSpec& spec = *plan.spec;
  const WarpProblem& problem = plan.image->problem;
  proto::ImageJobReport r;
  r.warp = warp_setup_report(problem);
  r.prealignment = prealignment_report(problem.prealignment());
  r.closest_approach = closest_approach_report(problem);
  r.trajectory = trajectory_report(problem);
  r.mirror = mirror_report(features_from_spec(*spec.warp), spec.warp->mirror);
  return r;
}

// Where the job's progress stands at the end of each stage: the stages' predicted seconds (stage_costs.hpp),
// summed in order, as shares of the whole; the Jacobian check is counted as a second verify. The maps (decode,
// sampling, encode and write, per map) come after the output grid's map, each an equal share.
struct ProgressPoints {
  double device_setup, map, maps, residuals, verify;
};

ProgressPoints progress_points(const JobPlan& plan, bool closed_form) {
  using proto::LatencyStage;
  StageWorkload work =
      image_workload(plan.header, plan.warp.width, plan.warp.height, plan.image->problem.size(), plan.warp.exact);
  work.pathlines = !closed_form;
  work.maps = plan.maps.size();
  const auto s = [&](LatencyStage stage) { return predicted_seconds(stage, work); };
  const double jacobian = plan.spec->options.jacobian_check ? s(LatencyStage::kVerify) : 0.0;
  const double maps =
      s(LatencyStage::kDecode) + s(LatencyStage::kSampling) + s(LatencyStage::kEncode) + s(LatencyStage::kWrite);
  double at = s(LatencyStage::kPlan);
  ProgressPoints p{};
  p.device_setup = at += s(LatencyStage::kDeviceSetup);
  p.map = at += s(LatencyStage::kPathlines);
  p.maps = at += maps;
  p.residuals = at += s(LatencyStage::kVerify);
  p.verify = at += jacobian;
  for (double* f : {&p.device_setup, &p.map, &p.maps, &p.residuals, &p.verify}) *f /= at;
  return p;
}

}  // namespace

JobOutput run_image_plan(const JobPlan& plan, BackendCache& backends, const std::filesystem::path& out_dir,
                         const JobLimits& limits, const RunControl& control, Clock::time_point start) {
  const WarpProblem& problem = plan.image->problem;
  proto::JobReport report;
  proto::StageTimings& stages = report.timings.stages;
  stages.add(proto::LatencyStage::kPlan, plan.seconds);
  // A zero field's warp is its closed form: no device is opened for it (the CPU backend measures its residuals).
  const bool closed_form = has_closed_form(problem);
  WarpBackend& backend = timed(report.timings.prepare_s, [&]() -> WarpBackend& {
    return closed_form ? backends.get(proto::DeviceSpec::cpu()) : backends.get(plan.spec->options.device);
  });
  if (!closed_form) stages.add(proto::LatencyStage::kDeviceSetup, *report.timings.prepare_s);
  const std::uint64_t retries_before = backend.double_retries();
  *report.timings.prepare_s += plan.seconds;
  const ProgressPoints at = progress_points(plan, closed_form);
  report_progress(control, at.device_setup);
  // The output grid's map, once for every map of the job.
  const OutputGridMap grid = timed(report.timings.warp_s, [&] {
    return map_output_grid(backend, problem, plan.header.width, plan.header.height, plan.warp, positions_needed(plan),
                           phase(control, at.device_setup, at.map));
  });
  stages.add(proto::LatencyStage::kPathlines, grid.map_s);
  const WarpCertificate& certificate = grid.certificate;
  report_progress(control, at.map);
  proto::ImageJobReport& sections = report.image.emplace(image_sections(plan));
  WarpedMaps maps = warp_maps(plan, grid, plan.warp, plan.spec->warp->mirror, out_dir, limits,
                              phase(control, at.map, at.maps), stages);
  report.timings.read_s = maps.read_s;
  *report.timings.warp_s += maps.sampling_s;
  sections.input = maps.reports.front().input;
  sections.output = maps.reports.front().output;
  if (plan.spec->is_set()) sections.maps = std::move(maps.reports);
  sections.residuals = timed(report.timings.residuals_s,
                             [&] { return residuals_report(backend, problem, phase(control, at.maps, at.residuals)); });
  stages.add(proto::LatencyStage::kVerify, *report.timings.residuals_s);
  if (plan.spec->options.jacobian_check) {
    sections.jacobian = timed(report.timings.jacobian_s, [&] {
      return output_jacobian(backend, problem, grid.width, grid.height, phase(control, at.residuals, at.verify));
    });
    stages.add(proto::LatencyStage::kVerify, *report.timings.jacobian_s);
  }
  report_progress(control, at.verify);
  report.timings.write_s = maps.write_s;
  report.backend = backend.name();
  report.double_retries = backend.double_retries() - retries_before;
  report.exact = certificate.exact;
  record_warp(report, certificate, closed_form);
  return finish_job(out_dir, std::move(maps.files), std::move(report), start, control);
}

}  // namespace texwarp::runner
