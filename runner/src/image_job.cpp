// Running an image job's plan: warp the texture, measure the constraint residuals (and on request the Jacobian
// over the output), write the warped image and the report.
#include "job_runs.hpp"

#include <algorithm>

#include "job_steps.hpp"
#include "texwarp/core/closed_form_warp.hpp"
#include "texwarp/core/constraint_residuals.hpp"
#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/sampling_report.hpp"
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
proto::JacobianReport output_jacobian(WarpBackend& backend, const WarpProblem& problem, const Image& warped,
                                      const RunControl& control) {
  const int step =
      std::max(1, (std::max(warped.width, warped.height) + kJacobianMaxGridSide - 1) / kJacobianMaxGridSide);
  std::vector<Point> grid;
  for (int y = 0; y < warped.height; y += step) {
    for (int x = 0; x < warped.width; x += step) grid.emplace_back(x + 0.5, y + 0.5);
  }
  const JacobianStats stats =
      summarize_determinants(warp_jacobian_determinants(backend, problem, grid, Direction::kInverse, control));
  return jacobian_report(stats, proto::JacobianEstimate::kVariationalEquation, step);
}

proto::ImageJobReport image_sections(const JobPlan& plan, const Image& warped) {
  const proto::JobSpec& spec = *plan.spec;
  const WarpProblem& problem = plan.image->problem;
  proto::ImageJobReport r;
  r.input = {plan.header.width, plan.header.height, plan.header.channels, plan.header.format};
  // The output's pixel format and channels are what the file holds (write_warped_image), known once it is written.
  r.output.file = plan.image_file;
  r.output.width = warped.width;
  r.output.height = warped.height;
  r.output.channels = warped.channels;
  r.output.interpolation = spec.output.interpolation;
  r.output.border = spec.output.border;
  r.warp = warp_setup_report(problem);
  r.prealignment = prealignment_report(problem.prealignment());
  r.closest_approach = closest_approach_report(problem);
  r.trajectory = trajectory_report(problem);
  r.mirror = mirror_report(features_from_spec(*spec.warp), spec.warp->mirror);
  return r;
}

// Where the job's progress stands at the end of each stage: the stages' predicted seconds (stage_costs.hpp),
// summed in order, as shares of the whole; the Jacobian check is counted as a second verify.
struct ProgressPoints {
  double device_setup, decode, warp, residuals, verify;
};

ProgressPoints progress_points(const JobPlan& plan, bool closed_form) {
  using proto::LatencyStage;
  StageWorkload work =
      image_workload(plan.header, plan.warp.width, plan.warp.height, plan.image->problem.size(), plan.warp.exact);
  work.pathlines = !closed_form;
  const auto s = [&](LatencyStage stage) { return predicted_seconds(stage, work); };
  const double jacobian = plan.spec->options.jacobian_check ? s(LatencyStage::kVerify) : 0.0;
  double at = s(LatencyStage::kPlan);
  ProgressPoints p{};
  p.device_setup = at += s(LatencyStage::kDeviceSetup);
  p.decode = at += s(LatencyStage::kDecode);
  p.warp = at += s(LatencyStage::kPathlines) + s(LatencyStage::kSampling);
  p.residuals = at += s(LatencyStage::kVerify);
  p.verify = at += jacobian;
  const double total = at + s(LatencyStage::kEncode) + s(LatencyStage::kWrite);
  for (double* f : {&p.device_setup, &p.decode, &p.warp, &p.residuals, &p.verify}) *f /= total;
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
  *report.timings.prepare_s += plan.seconds;
  const ProgressPoints at = progress_points(plan, closed_form);
  report_progress(control, at.device_setup);
  Image source = timed(report.timings.read_s, [&] {
    Image texture = read_texture(plan, limits);
    if (plan.spec->warp->mirror) mirror_image(texture);
    return texture;
  });
  stages.add(proto::LatencyStage::kDecode, *report.timings.read_s);
  report_progress(control, at.decode);
  WarpCertificate certificate;
  ImageWarpTimes warp_times;
  const Image warped = timed(report.timings.warp_s, [&] {
    return warp_image(backend, problem, std::move(source), plan.warp, phase(control, at.decode, at.warp), &certificate,
                      &warp_times);
  });
  record_warp_times(stages, warp_times);
  proto::ImageJobReport& sections = report.image.emplace(image_sections(plan, warped));
  sections.output.sampling = sampling_report(plan.warp, warp_times.sampling);
  sections.residuals = timed(report.timings.residuals_s,
                             [&] { return residuals_report(backend, problem, phase(control, at.warp, at.residuals)); });
  stages.add(proto::LatencyStage::kVerify, *report.timings.residuals_s);
  if (plan.spec->options.jacobian_check) {
    sections.jacobian = timed(report.timings.jacobian_s, [&] {
      return output_jacobian(backend, problem, warped, phase(control, at.residuals, at.verify));
    });
    stages.add(proto::LatencyStage::kVerify, *report.timings.jacobian_s);
  }
  report_progress(control, at.verify);
  std::vector<JobFile> files = {timed(
      report.timings.write_s, [&] { return write_warped_image(plan, warped, out_dir, stages, &sections.output); })};
  report.backend = backend.name();
  report.exact = certificate.exact;
  record_warp(report, certificate, closed_form);
  return finish_job(out_dir, std::move(files), std::move(report), start, control);
}

}  // namespace texwarp::runner
