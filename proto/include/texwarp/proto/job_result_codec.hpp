// JSON codec for JobResult (schema: proto/schema/job-result.schema.json); decoding is lenient like every
// response codec.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_result.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

nlohmann::json encode_job_result(const JobResult& result);
JobResult decode_job_result(const nlohmann::json& value, const JsonPath& path = {});

}  // namespace texwarp::proto
