// JSON codec for job batches: see job_batch_codec.hpp.
#include "texwarp/proto/job_batch_codec.hpp"

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {

JobBatch decode_job_batch(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  const auto& jobs = r.at("jobs");
  const JsonPath at = r.key_path("jobs");
  if (!jobs.is_array()) throw InputError(at, "expected an array of jobs, got " + json_type_name(jobs));
  if (jobs.empty()) throw InputError(at, "a batch holds at least one job");
  if (jobs.size() > kMaxBatchJobs) {
    throw InputError(at, "a batch holds at most " + std::to_string(kMaxBatchJobs) + " jobs, got " +
                             std::to_string(jobs.size()) + " (send several batches)");
  }
  r.reject_unknown_keys();
  JobBatch batch;
  batch.jobs.reserve(jobs.size());
  for (std::size_t i = 0; i < jobs.size(); ++i) batch.jobs.push_back(decode_job_spec(jobs[i], at.index(i)));
  return batch;
}

nlohmann::json encode_job_batch(const JobBatch& batch) {
  nlohmann::json jobs = nlohmann::json::array();
  for (const auto& job : batch.jobs) jobs.push_back(encode_job_spec(job));
  return {{"jobs", std::move(jobs)}};
}

nlohmann::json encode_job_batch_status(const JobBatchStatus& status) {
  nlohmann::json jobs = nlohmann::json::array();
  for (const auto& s : status.jobs) jobs.push_back(encode_job_status(s));
  return {{"jobs", std::move(jobs)}};
}

JobBatchStatus decode_job_batch_status(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  const auto& jobs = r.at("jobs");
  if (!jobs.is_array()) throw InputError(r.key_path("jobs"), "expected an array, got " + json_type_name(jobs));
  JobBatchStatus status;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    status.jobs.push_back(decode_job_status(jobs[i], r.key_path("jobs").index(i)));
  }
  return status;
}

}  // namespace texwarp::proto
