// JSON codec for JobStatus and JobPage (schema: proto/schema/job-status.schema.json). Responses are decoded
// leniently (a newer server may add keys); states and kinds must be known names.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_status.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

nlohmann::json encode_job_status(const JobStatus& status);  // with "links" to itself and, once succeeded, its result
JobStatus decode_job_status(const nlohmann::json& value, const JsonPath& path = {});

nlohmann::json encode_job_page(const JobPage& page);
JobPage decode_job_page(const nlohmann::json& value, const JsonPath& path = {});

}  // namespace texwarp::proto
