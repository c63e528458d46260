// The problem types of texwarpd's API: see problem_types.hpp.
#include "texwarp/server/problem_types.hpp"

#include <array>
#include <stdexcept>

namespace texwarp::server {
namespace {

using K = ErrorKind;

// Ordered as ErrorKind (checked below), so that a kind is its row's index.
constexpr std::array kTable = {
    ProblemType{K::kMalformedRequest, "malformed-request", "Malformed HTTP request", 400},
    ProblemType{K::kUnauthorized, "unauthorized", "Unauthorized", 401, 0, "WWW-Authenticate",
                "Bearer realm=\"texwarpd\""},
    ProblemType{K::kNotFound, "not-found", "Not found", 404},
    ProblemType{K::kMethodNotAllowed, "method-not-allowed", "Method not allowed", 405},
    ProblemType{K::kRequestTimeout, "request-timeout", "Request timeout", 408},
    ProblemType{K::kBodyTooLarge, "body-too-large", "Request body too large", 413},
    ProblemType{K::kUnsupportedMediaType, "unsupported-media-type", "Unsupported media type", 415},
    ProblemType{K::kHeaderTooLarge, "header-too-large", "Request header fields too large", 431},
    ProblemType{K::kTooManyConnections, "too-many-connections", "Too many connections", 503, 1},
    ProblemType{K::kBadQuery, "bad-query", "Bad query parameter", 400},
    ProblemType{K::kMalformedJson, "malformed-json", "Malformed JSON", 400},
    ProblemType{K::kInvalidJob, "invalid-job", "Invalid job", 422, 0, {}, {}, true},
    ProblemType{K::kBadIdempotencyKey, "bad-idempotency-key", "Bad Idempotency-Key", 400},
    ProblemType{K::kIdempotencyKeyInUse, "idempotency-key-in-use", "Request with this Idempotency-Key in progress", 409,
                1},
    ProblemType{K::kIdempotencyKeyReused, "idempotency-key-reused", "Idempotency-Key reused with a different body",
                422},
    ProblemType{K::kJobFinished, "job-finished", "Job already finished", 409},
    ProblemType{K::kNoResult, "no-result", "Job has no result", 409},
    ProblemType{K::kQueueFull, "queue-full", "Queue full", 429, 1},
    ProblemType{K::kShuttingDown, "shutting-down", "Server shutting down", 503, 5},
    ProblemType{K::kStorageFull, "insufficient-storage", "Insufficient storage", 507, 30, {}, {}, true},
    ProblemType{K::kStoreUnavailable, "store-unavailable", "Job store unavailable", 503, 2},
    ProblemType{K::kNumericalError, "numerical-error", "The method could not meet its guarantees", 0, 0, {}, {}, true},
    ProblemType{
        K::kAttemptsExhausted, "attempts-exhausted", "Job abandoned after repeated restarts", 0, 0, {}, {}, true},
    ProblemType{K::kInternal, "internal", "Internal server error", 500, 0, {}, {}, true},
};

constexpr bool ordered_as_kinds() {
  for (std::size_t i = 0; i < kTable.size(); ++i) {
    if (static_cast<std::size_t>(kTable[i].kind) != i) return false;
  }
  return static_cast<std::size_t>(K::kInternal) + 1 == kTable.size();
}
static_assert(ordered_as_kinds(), "one row per ErrorKind, in the enum's order");

}  // namespace

std::span<const ProblemType> problem_types() { return kTable; }

const ProblemType& problem_type(ErrorKind kind) { return kTable.at(static_cast<std::size_t>(kind)); }

proto::ProblemDetails to_problem(const ServiceError& error, const std::string& instance) {
  // A kind that only ends jobs never reaches a response unless by a bug: it is answered as an internal error.
  const ProblemType& own = problem_type(error.kind());
  const ProblemType& type = own.status != 0 ? own : problem_type(ErrorKind::kInternal);
  return {std::string(proto::kProblemTypePrefix) + std::string(type.slug),
          std::string(type.title),
          type.status,
          error.detail(),
          instance,
          error.path()};
}

int retry_after_s(const ServiceError& error) {
  return error.retry_after_s().value_or(problem_type(error.kind()).retry_after_s);
}

proto::ProblemDetails job_problem(ErrorKind kind, const std::string& detail, const std::string& path) {
  const ProblemType& type = problem_type(kind);
  if (!type.job_error) throw std::logic_error("problem type " + std::string(type.slug) + " is not a job's error");
  return {
      std::string(proto::kProblemTypePrefix) + std::string(type.slug), std::string(type.title), 0, detail, "", path};
}

}  // namespace texwarp::server
