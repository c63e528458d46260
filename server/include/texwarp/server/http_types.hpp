// The HTTP vocabulary shared by the router and the connection code: Beast's request header, the three kinds of
// responses texwarpd sends (JSON/text in memory, a file streamed from disk, headers only) and what the router
// decides about a request from its header, before any body is read.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include <boost/beast/http.hpp>

#include "texwarp/server/service_error.hpp"

namespace texwarp::server {

namespace http = boost::beast::http;

struct Route;

using RequestHeader = http::request_header<>;
using StringResponse = http::response<http::string_body>;
using FileResponse = http::response<http::file_body>;
using EmptyResponse = http::response<http::empty_body>;
using ApiResponse = std::variant<StringResponse, FileResponse, EmptyResponse>;

// Decided from the header alone.
struct RequestPlan {
  enum class Body { kMemory, kFile };
  std::string route = "unmatched";  // the route's pattern, for metrics and logs ("/v1/jobs/{id}")
  const Route* matched = nullptr;   // the route's row for this method (null: refused)
  bool quiet = false;               // logged at debug level (probes, scrapes)
  Body body = Body::kMemory;
  std::uint64_t body_limit = 0;         // bytes
  std::optional<ServiceError> refusal;  // answer this without reading the body (the connection then closes)
  std::shared_ptr<void> idempotency_claim;
  std::filesystem::path upload_file;  // Body::kFile: where the body is received
  bool off_io_thread = false;         // handle() parses, decodes or writes the body: run it off the I/O threads
};

}  // namespace texwarp::server
