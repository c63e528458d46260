// ClientError: what went wrong in a libtexwarp_client call, as a value (the library never throws across its API):
// a code to branch on, the HTTP status when the server answered, a message a person can act on, and the server's
// RFC 9457 problem (with the JSON path of the offending value) when it sent one.
#pragma once

#include <optional>
#include <string>

#include "texwarp/proto/problem_details.hpp"

namespace texwarp::client {

enum class ErrorCode {
  kInvalidArgument,  // the call's own arguments (bad server URL, unreadable local file, job that does not encode)
  kConnection,       // cannot connect, or the connection broke (once the retry budget is spent)
  kTimeout,          // no answer within the request timeout (once the retry budget is spent), or wait() ran out of time
  kHttp,             // the server refused the request (4xx, or 429/5xx once the retry budget is spent); see
                     // http_status and problem
  kProtocol,         // the server's answer is not what the API promises
  kIo,               // a local file could not be written
  kJobFailed,        // run(): the job ended failed; problem holds its error
  kJobCanceled,      // run(): the job ended canceled
  kInternal,         // an unexpected error inside the library
};

struct ClientError {
  ErrorCode code = ErrorCode::kInternal;
  int http_status = 0;  // 0 when no HTTP answer
  std::string message;
  std::optional<proto::ProblemDetails> problem;
};

const char* to_string(ErrorCode code);

}  // namespace texwarp::client
