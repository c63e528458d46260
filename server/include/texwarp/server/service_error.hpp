// ServiceError: a typed error of texwarpd (its kind, a detail that says what to fix, the offending JSON path),
// thrown by the service and the router. Which HTTP status, problem type and headers a kind gets is decided once, at
// the HTTP boundary, by the table of problem_types.hpp.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace texwarp::server {

// Every kind of error texwarpd reports; each is one problem type of the API (problem_types.hpp).
enum class ErrorKind {
  // The request itself (framing, access, routing, limits).
  kMalformedRequest,
  kUnauthorized,
  kNotFound,
  kMethodNotAllowed,
  kRequestTimeout,
  kBodyTooLarge,
  kUnsupportedMediaType,
  kHeaderTooLarge,
  kTooManyConnections,
  kBadQuery,
  // Jobs and their admission.
  kMalformedJson,
  kInvalidJob,
  kBadIdempotencyKey,
  kIdempotencyKeyInUse,
  kIdempotencyKeyReused,
  kJobFinished,
  kNoResult,
  kQueueFull,
  kShuttingDown,
  kStorageFull,
  kStoreUnavailable,  // the job store cannot be reached (a database restarting): nothing changed, retry
  // A failed job's end (also kInvalidJob, kStorageFull and kInternal).
  kNumericalError,
  kAttemptsExhausted,
  kInternal,
};

class ServiceError : public std::runtime_error {
 public:
  // `path`: the JSON path (or "?param") of the offending value, when there is one.
  ServiceError(ErrorKind kind, const std::string& detail, std::string path = {})
      : std::runtime_error(detail), kind_(kind), path_(std::move(path)) {}

  ErrorKind kind() const { return kind_; }
  std::string detail() const { return what(); }
  const std::string& path() const { return path_; }
  // Seconds to wait before retrying, when this occurrence knows better than its kind's default (a full queue).
  const std::optional<int>& retry_after_s() const { return retry_after_s_; }
  // Headers this occurrence adds (405's Allow).
  const std::vector<std::pair<std::string, std::string>>& headers() const { return headers_; }

  ServiceError& retry_after(int seconds) {
    retry_after_s_ = seconds;
    return *this;
  }
  ServiceError& header(std::string name, std::string value) {
    headers_.emplace_back(std::move(name), std::move(value));
    return *this;
  }

 private:
  ErrorKind kind_;
  std::string path_;
  std::optional<int> retry_after_s_;
  std::vector<std::pair<std::string, std::string>> headers_;
};

}  // namespace texwarp::server
