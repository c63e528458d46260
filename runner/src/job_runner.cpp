// Running and pre-checking jobs: see job_runner.hpp. A job is planned (job_plan.hpp), then its plan is run
// (image_job.cpp, mesh_job.cpp).
#include "texwarp/runner/job_runner.hpp"

#include "job_plan.hpp"
#include "job_runs.hpp"
#include "texwarp/core/memory_estimate.hpp"

namespace texwarp::runner {

std::uint64_t default_job_memory_bytes(int concurrent_jobs) { return default_memory_budget(concurrent_jobs); }

std::string warped_image_extension(const proto::OutputSpec& output) {
  if (output.texture && output.file_format == proto::FileFormat::kTiff) return "tx";
  return to_string(output.file_format);
}

std::string warped_image_file(const proto::OutputSpec& output) { return "warped." + warped_image_extension(output); }

std::string media_type_for(const std::string& file_name) {
  const auto dot = file_name.rfind('.');
  const std::string ext = dot == std::string::npos ? "" : file_name.substr(dot + 1);
  if (ext == "png") return "image/png";
  if (ext == "tiff" || ext == "tif" || ext == "tx") return "image/tiff";
  if (ext == "exr") return "image/x-exr";
  if (ext == "obj") return "model/obj";
  if (ext == "gltf") return "model/gltf+json";
  if (ext == "glb") return "model/gltf-binary";
  if (ext == "json") return "application/json";
  return "application/octet-stream";
}

void validate_job(const proto::JobSpec& spec, InputResolver& inputs, const JobLimits& limits) {
  plan_job(spec, inputs, limits, PlanScope::kSubmission);
}

JobOutput run_job(const proto::JobSpec& spec, InputResolver& inputs, BackendCache& backends,
                  const std::filesystem::path& out_dir, const JobLimits& limits, const RunControl& control) {
  const auto start = Clock::now();
  JobPlan plan = plan_job(spec, inputs, limits, PlanScope::kRun);
  if (plan.image) return run_image_plan(plan, backends, out_dir, limits, control, start);
  return run_mesh_plan(std::move(plan), backends, out_dir, limits, control, start);
}

}  // namespace texwarp::runner
