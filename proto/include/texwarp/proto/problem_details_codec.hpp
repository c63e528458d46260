// The JSON codec of ProblemDetails (problem_details.hpp): problem+json documents and a failed job's "error".
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/proto/json_path.hpp"
#include "texwarp/proto/problem_details.hpp"

namespace texwarp::proto {

nlohmann::json encode_problem(const ProblemDetails& problem);
// Lenient: unknown keys are ignored (problem documents may carry extensions); InputError if not an object.
ProblemDetails decode_problem(const nlohmann::json& value, const JsonPath& path = {});

}  // namespace texwarp::proto
