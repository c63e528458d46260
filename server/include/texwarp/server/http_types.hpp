// The HTTP vocabulary shared by the router and the connection code: Beast's request header, the three kinds of
// responses texwarpd sends (JSON/text in memory, a file streamed from disk, headers only), what the router decides
// about a request from its header, before any body is read, and an answer deferred without holding a thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
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

// An answer that comes later (a long poll), without holding a thread while it waits: the connection re-asks `poll`
// on its own strand every `interval` and whenever `subscribe`'s wake-up is called (from any thread), until `poll`
// answers; at `deadline` it asks once more with final = true, and then `poll` must answer.
struct DeferredAnswer {
  std::chrono::steady_clock::time_point deadline;
  std::chrono::milliseconds interval{200};
  std::function<std::optional<ApiResponse>(bool final)> poll;
  // Registers `wake`; the wake-ups stop when the returned token is destroyed. May be empty (timer only).
  std::function<std::shared_ptr<void>(std::function<void()> wake)> subscribe;
};

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
  // Set by a handler whose answer is deferred: handle()'s own answer is then ignored and this one awaited.
  std::optional<DeferredAnswer> deferred;
};

}  // namespace texwarp::server
