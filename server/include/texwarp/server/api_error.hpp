// ApiError: a request the API answers with an RFC 9457 problem (status, type slug, title, detail, JSON path),
// thrown by the service and the router and turned into application/problem+json once, at the HTTP boundary.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "texwarp/proto/problem_details.hpp"

namespace texwarp::server {

class ApiError : public std::runtime_error {
 public:
  // `slug` names the problem type (urn:texwarp:problem:<slug>); `detail` says what to fix.
  ApiError(int status, std::string slug, std::string title, std::string detail, std::string path = {})
      : std::runtime_error(detail),
        status_(status),
        slug_(std::move(slug)),
        title_(std::move(title)),
        detail_(std::move(detail)),
        path_(std::move(path)) {}

  int status() const { return status_; }
  const std::string& slug() const { return slug_; }
  const std::optional<int>& retry_after_s() const { return retry_after_s_; }
  const std::vector<std::pair<std::string, std::string>>& headers() const { return headers_; }

  ApiError& retry_after(int seconds) {
    retry_after_s_ = seconds;
    return *this;
  }
  ApiError& header(std::string name, std::string value) {
    headers_.emplace_back(std::move(name), std::move(value));
    return *this;
  }

  proto::ProblemDetails problem(const std::string& instance) const {
    return {std::string(proto::kProblemTypePrefix) + slug_, title_, status_, detail_, instance, path_};
  }

 private:
  int status_;
  std::string slug_;
  std::string title_;
  std::string detail_;
  std::string path_;
  std::optional<int> retry_after_s_;
  std::vector<std::pair<std::string, std::string>> headers_;
};

// 507 "insufficient-storage": the server's data folder is full, so nothing was stored; retry later.
inline ApiError storage_full_error(const std::string& what) {
  return ApiError(507, "insufficient-storage", "Insufficient storage",
                  "the server's storage is full, so " + what +
                      " was not stored; retry later (the operator must free space in the data folder)")
      .retry_after(60);
}

}  // namespace texwarp::server
