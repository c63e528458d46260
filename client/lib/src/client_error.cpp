// Names of client error codes: see client_error.hpp.
#include "texwarp/client/client_error.hpp"

namespace texwarp::client {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument:
      return "invalid_argument";
    case ErrorCode::kConnection:
      return "connection";
    case ErrorCode::kTimeout:
      return "timeout";
    case ErrorCode::kHttp:
      return "http";
    case ErrorCode::kProtocol:
      return "protocol";
    case ErrorCode::kIo:
      return "io";
    case ErrorCode::kJobFailed:
      return "job_failed";
    case ErrorCode::kJobCanceled:
      return "job_canceled";
    case ErrorCode::kWrongState:
      return "wrong_state";
    case ErrorCode::kInternal:
      return "internal";
    case ErrorCode::kStopped:
      return "stopped";
  }
  return "internal";
}

}  // namespace texwarp::client
