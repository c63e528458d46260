// The runs of a planned job (job_plan.hpp), one per kind: each writes its files into `out_dir` and returns them
// with the typed report; `start` is when the job began (its report's total_s). Progress 0 → 1 through `control`.
// A mesh job's run consumes its plan's mesh region (the mapping takes it over).
#pragma once

#include <filesystem>

#include "job_plan.hpp"
#include "job_steps.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/runner/job_runner.hpp"

namespace texwarp::runner {

JobOutput run_image_plan(const JobPlan& plan, BackendCache& backends, const std::filesystem::path& out_dir,
                         const JobLimits& limits, const RunControl& control, Clock::time_point start);

JobOutput run_mesh_plan(JobPlan&& plan, BackendCache& backends, const std::filesystem::path& out_dir,
                        const JobLimits& limits, const RunControl& control, Clock::time_point start);

}  // namespace texwarp::runner
