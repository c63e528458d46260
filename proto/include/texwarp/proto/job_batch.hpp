// JobBatch: the body of POST /v1/jobs:batch (1 to kMaxBatchJobs jobs, accepted all or none), and JobBatchStatus:
// its answer, the status of each job in the order given.
#pragma once

#include <cstddef>
#include <vector>

#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/job_status.hpp"

namespace texwarp::proto {

inline constexpr std::size_t kMaxBatchJobs = 1000;

struct JobBatch {
  std::vector<JobSpec> jobs;
};

struct JobBatchStatus {
  std::vector<JobStatus> jobs;  // in the batch's order
};

}  // namespace texwarp::proto
