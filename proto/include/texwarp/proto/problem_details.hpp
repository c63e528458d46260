// ProblemDetails: an error as RFC 9457 problem+json (type, title, status, detail, instance) plus `path`, the
// JSON path of the offending value when the error is about a request body. Also a failed job's `error`.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

struct ProblemDetails {
  std::string type = "about:blank";  // a URN "urn:texwarp:problem:<slug>" for texwarp's own kinds
  std::string title;                 // short, the same for every problem of this type
  int status = 0;                    // HTTP status (0 in a job's error)
  std::string detail;                // what went wrong and what to fix, for this occurrence
  std::string instance;              // the request path (or job) it is about
  std::string path;                  // JSON path of the offender ("$.warp.features[3].source"); may be empty
};

// Problem type URNs used by texwarp.
inline constexpr const char* kProblemTypePrefix = "urn:texwarp:problem:";

nlohmann::json encode_problem(const ProblemDetails& problem);
// Lenient: unknown keys are ignored (problem documents may carry extensions); InputError if not an object.
ProblemDetails decode_problem(const nlohmann::json& value, const JsonPath& path = {});

}  // namespace texwarp::proto
