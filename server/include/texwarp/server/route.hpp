// Route: one row of texwarpd's route table (method(s), path pattern, handler, access, body), the call a handler
// gets, and the lookup of a request's method and path in a table. The table itself is ApiRouter::routes(): 404,
// 405 with its Allow header, body limits, metrics labels and the check against openapi.json all derive from it.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "texwarp/server/http_types.hpp"
#include "texwarp/server/request_target.hpp"

namespace texwarp::server {

class ApiRouter;

// The values of a matched path's {name} segments.
class RouteParams {
 public:
  void add(std::string_view name, std::string value) { values_.emplace_back(name, std::move(value)); }
  // std::out_of_range for a name the pattern does not have.
  const std::string& operator[](std::string_view name) const;

 private:
  std::vector<std::pair<std::string_view, std::string>> values_;
};

// What a handler answers: the request and what the route lookup found.
struct RouteCall {
  const RequestHeader& header;
  const std::string& body;  // RouteBody::kJson's body (an upload is in plan.upload_file)
  RequestPlan& plan;
  const RequestTarget& target;
  const RouteParams& params;
};

enum class RouteAccess {
  kOpen,   // answered without a token (the probes)
  kToken,  // needs the bearer token when the server has one
};

enum class RouteBody {
  kNone,    // none expected: at most 64 KiB, read into memory
  kJson,    // a JSON document (application/json or +json), up to --max-job-body-mb, parsed off the I/O threads
  kUpload,  // raw bytes (not a form) received into a file, up to --max-blob-mb, stored off the I/O threads
};

struct Route {
  std::vector<http::verb> methods;  // HEAD where the route answers it (a handler's string answer loses its body)
  std::string_view pattern;         // "/v1/jobs/{id}/files/{name}": literal segments and {name} parameters; a parameter
                                    // may end its segment with a literal custom verb: "/v1/jobs/{id}:cancel"
  ApiResponse (ApiRouter::*handler)(const RouteCall&);
  RouteAccess access = RouteAccess::kToken;
  RouteBody body = RouteBody::kNone;
  bool idempotency_key = false;  // claims the Idempotency-Key header before the body is read
  bool quiet = false;            // its requests are logged at debug level (probes, scrapes)
};

// The parameters of `segments` when they match `pattern` (one segment per literal or {name}).
std::optional<RouteParams> match_pattern(std::string_view pattern, const std::vector<std::string>& segments);

struct RouteLookup {
  const Route* route = nullptr;       // the row of this method and path
  const Route* path_route = nullptr;  // the first row of this path (null: no route has this path)
  std::vector<http::verb> allowed;    // the path's methods in table order (405's Allow)
  RouteParams params;
};

RouteLookup find_route(std::span<const Route> table, http::verb method, const std::vector<std::string>& segments);

// "POST, GET"
std::string allow_header(const std::vector<http::verb>& methods);

}  // namespace texwarp::server
