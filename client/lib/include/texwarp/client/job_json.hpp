// A job as JSON text and back, for callers that hold jobs as text (files, Python dicts, DCC scene data) and must not
// depend on a JSON library: the same checks as the server's decoder, errors as values.
#pragma once

#include <string>
#include <string_view>

#include "texwarp/client/result.hpp"
#include "texwarp/proto/export.hpp"
#include "texwarp/proto/job_spec.hpp"

namespace texwarp::client {

// A job document (the body of POST /v1/jobs) decoded and checked. ErrorCode::kInvalidArgument when it is not JSON
// or not a valid job; its message names `source` and the place, problem->path the JSON path ("$.warp.alpha").
TEXWARP_API Result<proto::JobSpec> parse_job(std::string_view json_text, const std::string& source = "job");
// The job as its JSON document (compact); parse_job(job_json(job)) gives `job` back.
TEXWARP_API Result<std::string> job_json(const proto::JobSpec& job);

}  // namespace texwarp::client
