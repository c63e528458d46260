// ClientError: what went wrong in a libtexwarp_client call, as a value (the library never throws across its API):
// a code to branch on, the HTTP status when the server answered, a message a person can act on, and the server's
// RFC 9457 problem (with the JSON path of the offending value) when it sent one, and for a batch the index of the job
// the problem is about.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "texwarp/proto/export.hpp"
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
  kWrongState,       // the job is not in a state the call applies to: cancel() of a finished job, purge() of an
                     // unfinished one (nothing was changed, except as cancel() says)
  kInternal,         // an unexpected error inside the library
  kStopped,          // wait() (or run()) gave up because WaitOptions::stop was requested; the job goes on
};

struct ClientError {
  ErrorCode code = ErrorCode::kInternal;
  int http_status = 0;  // 0 when no HTTP answer
  std::string message;
  std::optional<proto::ProblemDetails> problem;
  std::optional<std::size_t> batch_index;  // submit_batch(): the job (0-based) the problem's path names
};

TEXWARP_API const char* to_string(ErrorCode code);

}  // namespace texwarp::client
