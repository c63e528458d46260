// JSON codec for JobBatch (schema: proto/schema/job-batch.schema.json) and JobBatchStatus
// (job-batch-status.schema.json). A batch decodes strictly: each job as decode_job_spec, its errors at
// "$.jobs[<i>]…"; the answer decodes leniently, as job statuses do.
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_batch.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

// Strict: InputError at "$.jobs" for a batch that is empty or longer than kMaxBatchJobs, at "$.jobs[<i>]…" for the
// first invalid job (every job is decoded before anything is accepted), at the key for an unknown key.
JobBatch decode_job_batch(const nlohmann::json& value, const JsonPath& path = {});
// The canonical form: each job as encode_job_spec writes it.
nlohmann::json encode_job_batch(const JobBatch& batch);

nlohmann::json encode_job_batch_status(const JobBatchStatus& status);
JobBatchStatus decode_job_batch_status(const nlohmann::json& value, const JsonPath& path = {});

}  // namespace texwarp::proto
