// The JSON codec of a job's labels (job_labels.hpp): the job body's "labels" object.
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_labels.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

// A "labels" object of string values (each pair checked, errors at $.labels.<key>; at most kMaxJobLabels).
JobLabels decode_job_labels(const nlohmann::json& value, const JsonPath& path);
nlohmann::json encode_job_labels(const JobLabels& labels);

}  // namespace texwarp::proto
