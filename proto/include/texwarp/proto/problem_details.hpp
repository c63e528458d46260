// ProblemDetails: an error as RFC 9457 problem+json (type, title, status, detail, instance) plus `path`, the
// JSON path of the offending value when the error is about a request body. Also a failed job's `error`.
// JSON codec: problem_details_codec.hpp.
#pragma once

#include <string>

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

}  // namespace texwarp::proto
