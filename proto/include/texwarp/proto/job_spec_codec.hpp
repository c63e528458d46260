// JSON codec for JobSpec (schema: proto/schema/job.schema.json). Decoding is strict: unknown keys, wrong types,
// out-of-range values and a job that is neither or both of image and mesh are InputErrors naming the JSON path.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

// The whole job, mesh parts included: a client can validate a job offline by decoding it.
JobSpec decode_job_spec(const nlohmann::json& value, const JsonPath& path = {});

// The canonical form: every option written out, the image as given (base64 re-encoded).
nlohmann::json encode_job_spec(const JobSpec& spec);

// A blob id: "sha256:" followed by 64 lowercase hex digits.
bool is_blob_id(const std::string& id);

}  // namespace texwarp::proto
