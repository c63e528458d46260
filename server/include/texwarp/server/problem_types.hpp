// The problem types of texwarpd's API in one table: for each ErrorKind its type slug (urn:texwarp:problem:<slug>),
// title, HTTP status, default Retry-After and extra header, and whether a failed job's error may carry it. The HTTP
// boundary and the job records derive every problem from it; openapi.json's x-problem-types is tested against it.
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "texwarp/proto/problem_details.hpp"
#include "texwarp/server/service_error.hpp"

namespace texwarp::server {

struct ProblemType {
  ErrorKind kind;
  std::string_view slug;
  std::string_view title;
  int status = 0;                     // HTTP status of a response with this problem; 0: only ever a failed job's error
  int retry_after_s = 0;              // Retry-After of such a response (0: none) unless the occurrence gives its own
  std::string_view header_name = {};  // a header every such response carries (401's WWW-Authenticate)
  std::string_view header_value = {};
  bool job_error = false;  // a failed job's recorded error may be of this type
};

// The whole table, one row per ErrorKind.
std::span<const ProblemType> problem_types();
const ProblemType& problem_type(ErrorKind kind);

// The problem a response answers with: status, type, title and detail, `instance` the request's path.
proto::ProblemDetails to_problem(const ServiceError& error, const std::string& instance);
// Retry-After of a response with this error (0: none).
int retry_after_s(const ServiceError& error);
// The problem recorded as a failed job's error (no HTTP status: the job's status request itself succeeds).
proto::ProblemDetails job_problem(ErrorKind kind, const std::string& detail, const std::string& path = {});

}  // namespace texwarp::server
