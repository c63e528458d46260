// The HTTP routes of texwarpd: see api_router.hpp.
#include "texwarp/server/api_router.hpp"

#include <openssl/crypto.h>

#include <algorithm>
#include <charconv>
#include <stdexcept>
#include <vector>

#include "texwarp/proto/blob_info_codec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_batch_codec.hpp"
#include "texwarp/proto/job_labels.hpp"
#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/node_status_codec.hpp"
#include "texwarp/proto/problem_details_codec.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/server/declared_length.hpp"
#include "texwarp/server/embedded_documents.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/problem_types.hpp"
#include "texwarp/server/request_target.hpp"
#include "texwarp/server/storage_full.hpp"

namespace texwarp::server {
namespace {

constexpr std::uint64_t kSmallBodyLimit = 64 << 10;  // routes that take no body
constexpr int kDefaultPageSize = 50;
constexpr int kMaxPageSize = 500;
constexpr std::size_t kMaxIdempotencyKeyLength = 255;
constexpr int kMaxWaitS = 60;  // GET /v1/jobs/{id}?wait=S
constexpr auto kWaitRecheck = std::chrono::milliseconds(200);

std::string path_only(std::string_view target) { return std::string(target.substr(0, target.find('?'))); }

// The media type of a Content-Type value, without parameters or spaces, in lower case ("multipart/form-data").
std::string media_type(std::string_view content_type) {
  std::string t(content_type.substr(0, content_type.find(';')));
  t.erase(std::remove_if(t.begin(), t.end(), [](unsigned char c) { return std::isspace(c); }), t.end());
  std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return t;
}

bool is_json_media_type(std::string_view content_type) {
  const std::string t = media_type(content_type);
  return t == "application/json" || (t.size() > 5 && t.compare(t.size() - 5, 5, "+json") == 0);
}

// The credentials of `Authorization: Bearer <token>`; the scheme is case-insensitive (RFC 9110 §11.1) and spaces
// around scheme and token are tolerated. nullopt when the header is absent, empty or of another scheme.
std::optional<std::string_view> bearer_credentials(std::string_view auth) {
  constexpr std::string_view kSpaces = " \t";
  const auto trim = [&](std::string_view v) {
    const auto first = v.find_first_not_of(kSpaces);
    if (first == std::string_view::npos) return std::string_view();
    return v.substr(first, v.find_last_not_of(kSpaces) - first + 1);
  };
  auth = trim(auth);
  const auto space = auth.find_first_of(kSpaces);
  if (space == std::string_view::npos || !boost::beast::iequals(auth.substr(0, space), "Bearer")) return std::nullopt;
  const std::string_view token = trim(auth.substr(space));
  if (token.empty()) return std::nullopt;
  return token;
}

bool token_matches(std::string_view given, const std::string& token) {
  if (given.size() != token.size()) return false;
  return CRYPTO_memcmp(given.data(), token.data(), token.size()) == 0;
}

StringResponse json_response(http::status status, const nlohmann::json& body, unsigned version) {
  StringResponse res{status, version};
  res.set(http::field::content_type, "application/json");
  res.set(http::field::cache_control, "no-store");
  res.body() = proto::safe_dump(body) + "\n";
  res.prepare_payload();
  return res;
}

StringResponse text_response(http::status status, std::string body, const char* content_type, unsigned version) {
  StringResponse res{status, version};
  res.set(http::field::content_type, content_type);
  res.body() = std::move(body);
  res.prepare_payload();
  return res;
}

std::string query_value(const RequestTarget& t, const std::string& key) {
  for (const auto& [k, v] : t.query) {
    if (k == key) return v;
  }
  return {};
}

void reject_unknown_query(const RequestTarget& t, std::initializer_list<const char*> known) {
  for (const auto& parameter : t.query) {
    const std::string& k = parameter.first;  // not a structured binding: clang 14 lets no lambda capture one
    if (std::none_of(known.begin(), known.end(), [&](const char* n) { return k == n; })) {
      throw ServiceError(ErrorKind::kBadQuery, "unknown query parameter \"" + proto::utf8_prefix(k, 40) + "\"",
                         "?" + proto::utf8_prefix(k, 40));
    }
  }
}

// A file streamed from disk (GET) or only its header (HEAD).
ApiResponse file_response(http::verb method, const std::filesystem::path& path, const std::string& media_type,
                          const std::string& etag, unsigned version) {
  if (method == http::verb::head) {
    EmptyResponse res{http::status::ok, version};
    res.set(http::field::content_type, media_type);
    res.set(http::field::etag, etag);
    res.content_length(std::filesystem::file_size(path));
    return res;
  }
  FileResponse res{http::status::ok, version};
  boost::beast::error_code ec;
  res.body().open(path.c_str(), boost::beast::file_mode::scan, ec);
  if (ec) throw std::runtime_error("cannot open " + path.string() + ": " + ec.message());
  res.set(http::field::content_type, media_type);
  res.set(http::field::etag, etag);
  res.prepare_payload();
  return res;
}

// The answer to a cancel or a delete: 200 canceled (it was queued), 202 cancel requested (running), 204 purged.
ApiResponse delete_response(const DeleteResult& r, unsigned version) {
  switch (r.action) {
    case DeleteResult::Action::kPurged:
      return EmptyResponse{http::status::no_content, version};
    case DeleteResult::Action::kCancelRequested:
      return json_response(http::status::accepted, proto::encode_job_status(r.status), version);
    case DeleteResult::Action::kCanceled:
      break;
  }
  return json_response(http::status::ok, proto::encode_job_status(r.status), version);
}

}  // namespace

unsigned response_status(const ApiResponse& response) {
  return std::visit([](const auto& r) { return r.result_int(); }, response);
}

std::span<const Route> ApiRouter::routes() {
  using V = http::verb;
  using R = ApiRouter;
  static const std::vector<Route> kRoutes = {
      {{V::get, V::head}, "/livez", &R::livez, RouteAccess::kOpen, RouteBody::kNone, false, true},
      {{V::get, V::head}, "/readyz", &R::readyz, RouteAccess::kOpen, RouteBody::kNone, false, true},
      {{V::get}, "/metrics", &R::metrics, RouteAccess::kToken, RouteBody::kNone, false, true},
      {{V::get}, "/v1/openapi.json", &R::openapi},
      {{V::get}, "/v1/schemas/{name}", &R::schema},
      {{V::post}, "/v1/blobs", &R::upload_blob, RouteAccess::kToken, RouteBody::kUpload},
      {{V::get, V::head}, "/v1/blobs/{id}", &R::get_blob},
      {{V::post}, "/v1/jobs", &R::submit_job, RouteAccess::kToken, RouteBody::kJson, true},
      {{V::get}, "/v1/jobs", &R::list_jobs},
      {{V::post}, "/v1/jobs:batch", &R::submit_batch, RouteAccess::kToken, RouteBody::kJson, true},
      {{V::get}, "/v1/jobs/{id}", &R::get_job},
      {{V::delete_}, "/v1/jobs/{id}", &R::delete_job},
      {{V::post}, "/v1/jobs/{id}:cancel", &R::cancel_job},
      {{V::get}, "/v1/jobs/{id}/result", &R::get_result},
      {{V::get, V::head}, "/v1/jobs/{id}/files/{name}", &R::get_result_file},
      {{V::get}, "/v1/nodes", &R::list_nodes},
  };
  return kRoutes;
}

bool ApiRouter::is_open_path(std::string_view target) {
  const RouteLookup found = find_route(routes(), http::verb::get, parse_request_target(target).segments);
  return found.path_route != nullptr && found.path_route->access == RouteAccess::kOpen;
}

ApiRouter::ApiRouter(const ServerConfig& config, JobService& service, Metrics& metrics)
    : config_(config), service_(service), metrics_(metrics) {}

// Members although they read no member: the connection code calls problem() on its router, and the route table holds
// the handlers as member pointers (&R::livez).
// NOLINTNEXTLINE(readability-convert-member-functions-to-static)
StringResponse ApiRouter::problem(const ServiceError& error, const std::string& instance, unsigned version,
                                  const std::string& request_id) const {
  const proto::ProblemDetails details = to_problem(error, instance);
  const ProblemType& type = problem_type(error.kind());
  StringResponse res{static_cast<http::status>(details.status), version};
  res.set(http::field::content_type, "application/problem+json");
  res.set(http::field::cache_control, "no-store");
  if (!request_id.empty()) res.set("X-Request-Id", request_id);
  if (const int s = retry_after_s(error); s > 0) res.set(http::field::retry_after, std::to_string(s));
  if (!type.header_name.empty()) res.set(type.header_name, type.header_value);
  for (const auto& [name, value] : error.headers()) res.set(name, value);
  res.body() = proto::safe_dump(proto::encode_problem(details)) + "\n";
  res.prepare_payload();
  return res;
}

RequestPlan ApiRouter::plan(const RequestHeader& header) {
  RequestPlan plan;
  plan.body_limit = kSmallBodyLimit;
  const RouteLookup found = find_route(routes(), header.method(), parse_request_target(header.target()).segments);
  if (found.path_route != nullptr) {
    plan.route = std::string(found.path_route->pattern);
    plan.quiet = found.path_route->quiet;
  }
  // Authentication comes first: without a valid token nothing but the probes says anything, not even "no route".
  const bool open_route = found.path_route != nullptr && found.path_route->access == RouteAccess::kOpen;
  if (!config_.token.empty() && !open_route) {
    const auto credentials = bearer_credentials(header[http::field::authorization]);
    if (!credentials || !token_matches(*credentials, config_.token)) {
      plan.refusal =
          ServiceError(ErrorKind::kUnauthorized, credentials ? "the bearer token is not valid for this server"
                                                             : "this server requires `Authorization: Bearer <token>`");
      return plan;
    }
  }
  if (found.path_route == nullptr) {
    plan.refusal =
        ServiceError(ErrorKind::kNotFound, "no route " + proto::utf8_prefix(path_only(header.target()), 120) +
                                               " (see GET /v1/openapi.json for the API)");
    return plan;
  }
  if (found.route == nullptr) {
    plan.refusal =
        ServiceError(ErrorKind::kMethodNotAllowed, std::string(header.method_string()) + " is not allowed on " +
                                                       plan.route + "; use " + allow_header(found.allowed))
            .header("Allow", allow_header(found.allowed));
    return plan;
  }
  plan.matched = found.route;
  plan_body(header, *found.route, plan);
  if (!plan.refusal && found.route->idempotency_key) plan_idempotency_key(header, plan);
  return plan;
}

void ApiRouter::plan_body(const RequestHeader& header, const Route& route, RequestPlan& plan) {
  if (route.body == RouteBody::kUpload) {
    plan.body_limit = config_.max_blob_bytes;
    plan.off_io_thread = true;
    if (const std::string type = media_type(header[http::field::content_type]); type.rfind("multipart/", 0) == 0) {
      plan.refusal = ServiceError(ErrorKind::kUnsupportedMediaType,
                                  "POST " + plan.route + " takes the file's bytes as they are, not a form (got \"" +
                                      proto::utf8_prefix(type, 60) +
                                      "\"); send e.g. `curl --data-binary @x.png -H 'Content-Type: "
                                      "application/octet-stream' <server>" +
                                      plan.route + "`");
      return;
    }
    plan.body = RequestPlan::Body::kFile;
    plan.upload_file = service_.blobs().temp_path();
  } else if (route.body == RouteBody::kJson) {
    plan.body_limit = config_.max_job_body_bytes;
    plan.off_io_thread = true;
    if (!is_json_media_type(header[http::field::content_type])) {
      plan.refusal = ServiceError(ErrorKind::kUnsupportedMediaType,
                                  "send the job as JSON with `Content-Type: application/json` (got \"" +
                                      proto::utf8_prefix(header[http::field::content_type], 60) + "\")");
      return;
    }
  }
  const std::optional<std::uint64_t> n = declared_content_length(header[http::field::content_length]);
  if (n && *n > plan.body_limit) {
    plan.refusal = ServiceError(
        ErrorKind::kBodyTooLarge,
        "the body has " + std::to_string(*n) + " bytes; this route accepts at most " + std::to_string(plan.body_limit) +
            (route.body == RouteBody::kJson ? " (upload large images with POST /v1/blobs and refer to them by id)"
                                            : ""));
  }
}

void ApiRouter::plan_idempotency_key(const RequestHeader& header, RequestPlan& plan) {
  const auto key = header["Idempotency-Key"];
  if (key.empty()) return;
  const bool printable = std::all_of(key.begin(), key.end(), [](char c) { return c > 0x20 && c < 0x7f; });
  if (key.size() > kMaxIdempotencyKeyLength || !printable) {
    plan.refusal = ServiceError(ErrorKind::kBadIdempotencyKey,
                                "Idempotency-Key must be 1 to 255 visible ASCII characters (a UUID is a good choice)");
    return;
  }
  try {
    plan.idempotency_claim = service_.claim_idempotency_key(std::string(key));
  } catch (const ServiceError& e) {
    plan.refusal = e;
  }
}

ApiResponse ApiRouter::guarded(const std::function<ApiResponse()>& answer, const std::string& instance,
                               unsigned version, const std::string& route, const std::string& request_id) const {
  try {
    return answer();
  } catch (const ServiceError& e) {
    return problem(e, instance, version, request_id);
  } catch (const StoreUnavailable& e) {
    log_event(LogLevel::kWarn, "the job store is unavailable",
              {{"request_id", request_id}, {"route", route}, {"error", e.what()}});
    return problem(ServiceError(ErrorKind::kStoreUnavailable,
                                "the job store cannot be reached right now; nothing was changed; retry after the "
                                "time given"),
                   instance, version, request_id);
  } catch (const std::exception& e) {
    log_event(LogLevel::kError, "internal error", {{"request_id", request_id}, {"route", route}, {"error", e.what()}});
    return problem(ServiceError(ErrorKind::kInternal, "the server could not answer this request; quote request id " +
                                                          request_id + " when reporting it"),
                   instance, version, request_id);
  }
}

ApiResponse ApiRouter::handle(const RequestHeader& header, const std::string& body, RequestPlan& plan,
                              const std::string& request_id) {
  const std::string instance = path_only(header.target());
  const unsigned version = header.version();
  const bool head = header.method() == http::verb::head;
  // What every answer gets on its way out: the request id, and for HEAD the same header without a body.
  const auto finish = [request_id, head](ApiResponse response) -> ApiResponse {
    std::visit([&](auto& r) { r.set("X-Request-Id", request_id); }, response);
    if (head) {
      if (auto* full = std::get_if<StringResponse>(&response)) {
        EmptyResponse empty{full->result(), full->version()};
        for (const auto& field : *full) empty.set(field.name_string(), field.value());
        empty.content_length(full->body().size());
        return empty;
      }
    }
    return response;
  };
  ApiResponse response = guarded(
      [&]() -> ApiResponse {
        if (plan.refusal) return problem(*plan.refusal, instance, version, request_id);
        if (plan.matched == nullptr) throw std::logic_error("a request without a route was not refused");
        const RequestTarget target = parse_request_target(header.target());
        const auto params = match_pattern(plan.matched->pattern, target.segments);
        if (!params) throw std::logic_error("the request's path does not match its planned route");
        return (this->*plan.matched->handler)(RouteCall{header, body, plan, target, *params});
      },
      instance, version, plan.route, request_id);
  if (plan.deferred) {
    // The deferred answer gets the same treatment as an immediate one: errors become problems, and `finish`.
    plan.deferred->poll = [this, poll = std::move(plan.deferred->poll), finish, instance, version, route = plan.route,
                           request_id](bool final) -> std::optional<ApiResponse> {
      std::optional<ApiResponse> answer;
      bool threw = true;
      ApiResponse error = guarded(
          [&]() -> ApiResponse {
            answer = poll(final);
            threw = false;
            return EmptyResponse{};
          },
          instance, version, route, request_id);
      if (threw) answer = std::move(error);
      if (!answer) return std::nullopt;  // no change yet
      return finish(std::move(*answer));
    };
  }
  return finish(std::move(response));
}

ApiResponse ApiRouter::livez(const RouteCall& call) {  // NOLINT(readability-convert-member-functions-to-static)
  return json_response(http::status::ok, {{"status", "ok"}}, call.header.version());
}

ApiResponse ApiRouter::readyz(const RouteCall& call) {
  const Readiness r = service_.readiness();
  const nlohmann::json j = {{"status", r.status}, {"checks", r.checks}};
  auto res = json_response(r.ready ? http::status::ok : http::status::service_unavailable, j, call.header.version());
  if (!r.ready) res.set(http::field::retry_after, "5");
  return res;
}

ApiResponse ApiRouter::metrics(const RouteCall& call) {
  return text_response(http::status::ok, metrics_.render(service_.gauges()), "text/plain; version=0.0.4; charset=utf-8",
                       call.header.version());
}

namespace {

StringResponse document_response(const std::string& name, unsigned version) {
  const auto doc = embedded_document(name);
  if (!doc) {
    throw ServiceError(ErrorKind::kNotFound,
                       "no schema \"" + proto::utf8_prefix(name, 60) + "\" (see GET /v1/openapi.json)");
  }
  auto res = text_response(http::status::ok, std::string(*doc), "application/json", version);
  res.set(http::field::cache_control, "max-age=300");
  return res;
}

}  // namespace

ApiResponse ApiRouter::openapi(const RouteCall& call) {  // NOLINT(readability-convert-member-functions-to-static)
  return document_response("openapi.json", call.header.version());
}

ApiResponse ApiRouter::schema(const RouteCall& call) {  // NOLINT(readability-convert-member-functions-to-static)
  return document_response(call.params["name"], call.header.version());
}

ApiResponse ApiRouter::upload_blob(const RouteCall& call) {
  proto::BlobInfo info;
  try {
    info = service_.adopt_blob(call.plan.upload_file);
  } catch (const std::filesystem::filesystem_error& e) {
    if (e.code() == std::errc::no_space_on_device || e.code() == std::errc::file_too_large) {
      throw storage_full_error("the upload was not stored");
    }
    throw;
  }
  log_event(LogLevel::kDebug, "blob stored", {{"blob", info.id}, {"bytes", info.bytes}, {"created", info.created}});
  auto res = json_response(info.created ? http::status::created : http::status::ok, proto::encode_blob_info(info),
                           call.header.version());
  res.set(http::field::location, "/v1/blobs/" + info.id);
  return res;
}

ApiResponse ApiRouter::get_blob(const RouteCall& call) {
  const std::string& id = call.params["id"];
  if (!proto::is_blob_id(id) || !service_.blobs().contains(id)) {
    throw ServiceError(ErrorKind::kNotFound, "there is no blob \"" + proto::utf8_prefix(id, 80) + "\" on this server");
  }
  return file_response(call.header.method(), service_.blobs().path_of(id), "application/octet-stream",
                       "\"" + id.substr(7) + "\"", call.header.version());
}

ApiResponse ApiRouter::submit_job(const RouteCall& call) {
  reject_unknown_query(call.target, {});
  const auto key = call.header["Idempotency-Key"];
  const SubmitResult r = service_.submit(call.body, key.empty() ? std::nullopt : std::optional<std::string>(key));
  auto res = json_response(http::status::accepted, proto::encode_job_status(r.status), call.header.version());
  res.set(http::field::location, "/v1/jobs/" + r.status.id);
  if (r.replayed) res.set("Idempotent-Replayed", "true");
  return res;
}

ApiResponse ApiRouter::submit_batch(const RouteCall& call) {
  reject_unknown_query(call.target, {});
  const auto key = call.header["Idempotency-Key"];
  const BatchResult r = service_.submit_batch(call.body, key.empty() ? std::nullopt : std::optional<std::string>(key));
  auto res = json_response(http::status::created, proto::encode_job_batch_status({r.jobs}), call.header.version());
  if (r.replayed) res.set("Idempotent-Replayed", "true");
  return res;
}

ApiResponse ApiRouter::list_jobs(const RouteCall& call) {
  const RequestTarget& t = call.target;
  reject_unknown_query(t, {"limit", "cursor", "state", "label"});
  int limit = kDefaultPageSize;
  if (const std::string v = query_value(t, "limit"); !v.empty()) {
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), limit);
    if (ec != std::errc() || end != v.data() + v.size() || limit < 1 || limit > kMaxPageSize) {
      throw ServiceError(ErrorKind::kBadQuery,
                         "limit: expected an integer from 1 to " + std::to_string(kMaxPageSize) + ", got \"" +
                             proto::utf8_prefix(v, 20) + "\"",
                         "?limit");
    }
  }
  std::optional<proto::JobState> state;
  if (const std::string v = query_value(t, "state"); !v.empty()) {
    try {
      state = proto::parse_enum<proto::JobState>(v, proto::InputLocation::flag("?state"));
    } catch (const InputError& e) {
      throw ServiceError(ErrorKind::kBadQuery, e.what(), "?state");
    }
  }
  Labels labels;
  for (const auto& [k, v] : t.query) {
    if (k != "label") continue;
    const auto eq = v.find('=');
    if (eq == std::string::npos) {
      throw ServiceError(ErrorKind::kBadQuery, "label: expected KEY=VALUE, got \"" + proto::utf8_prefix(v, 80) + "\"",
                         "?label");
    }
    const std::string key = v.substr(0, eq);
    const std::string value = v.substr(eq + 1);
    try {
      const auto at = proto::InputLocation::flag("?label");
      check_job_label(key, value, at, at);
    } catch (const InputError& e) {
      throw ServiceError(ErrorKind::kBadQuery, e.what(), "?label");
    }
    if (labels.size() == proto::kMaxJobLabels && labels.count(key) == 0) {
      throw ServiceError(ErrorKind::kBadQuery,
                         "label: at most " + std::to_string(proto::kMaxJobLabels) + " labels to filter on", "?label");
    }
    if (const auto [it, inserted] = labels.emplace(key, value); !inserted && it->second != value) {
      throw ServiceError(ErrorKind::kBadQuery,
                         "label: " + key + " is given twice with different values (no job can match)", "?label");
    }
  }
  return json_response(http::status::ok,
                       proto::encode_job_page(service_.list(query_value(t, "cursor"), limit, state, labels)),
                       call.header.version());
}

ApiResponse ApiRouter::get_job(const RouteCall& call) {
  const RequestTarget& t = call.target;
  reject_unknown_query(t, {"wait"});
  int wait_s = 0;
  const bool has_wait = std::any_of(t.query.begin(), t.query.end(), [](const auto& q) { return q.first == "wait"; });
  if (has_wait) {
    const std::string v = query_value(t, "wait");
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), wait_s);
    if (v.empty() || ec != std::errc() || end != v.data() + v.size() || wait_s < 0 || wait_s > kMaxWaitS) {
      throw ServiceError(ErrorKind::kBadQuery,
                         "wait: expected whole seconds from 0 to " + std::to_string(kMaxWaitS) + ", got \"" +
                             proto::utf8_prefix(v, 20) + "\"",
                         "?wait");
    }
  }
  const std::string id = call.params["id"];
  const proto::JobStatus now = service_.status(id);
  const unsigned version = call.header.version();
  if (wait_s == 0 || proto::is_terminal(now.state))
    return json_response(http::status::ok, proto::encode_job_status(now), version);
  // Long poll: answered at the first change of state, or at the deadline with the state then. No thread waits: the
  // connection re-reads the row every kWaitRecheck (changes made by other nodes) and at once when this node
  // changes the job.
  DeferredAnswer deferred;
  deferred.deadline = std::chrono::steady_clock::now() + std::chrono::seconds(wait_s);
  deferred.interval = kWaitRecheck;
  deferred.poll = [this, id, version, arrived = now.state](bool final) -> std::optional<ApiResponse> {
    const proto::JobStatus s = service_.status(id);
    if (s.state == arrived && !final) return std::nullopt;
    return json_response(http::status::ok, proto::encode_job_status(s), version);
  };
  deferred.subscribe = [this, id](std::function<void()> wake) { return service_.watch(id, std::move(wake)); };
  call.plan.deferred = std::move(deferred);
  return EmptyResponse{http::status::ok, version};
}

ApiResponse ApiRouter::cancel_job(const RouteCall& call) {
  reject_unknown_query(call.target, {});
  return delete_response(service_.cancel(call.params["id"]), call.header.version());
}

ApiResponse ApiRouter::delete_job(const RouteCall& call) {
  reject_unknown_query(call.target, {});
  return delete_response(service_.remove(call.params["id"]), call.header.version());
}

ApiResponse ApiRouter::list_nodes(const RouteCall& call) {
  reject_unknown_query(call.target, {});
  return json_response(http::status::ok, proto::encode_node_list(service_.nodes()), call.header.version());
}

ApiResponse ApiRouter::get_result(const RouteCall& call) {
  return json_response(http::status::ok, proto::encode_job_result(service_.result(call.params["id"])),
                       call.header.version());
}

ApiResponse ApiRouter::get_result_file(const RouteCall& call) {
  std::string media_type;
  std::string sha256;
  const auto path = service_.result_file(call.params["id"], call.params["name"], &media_type, &sha256);
  const std::string etag = "\"" + sha256 + "\"";
  if (call.header[http::field::if_none_match] == etag) {
    EmptyResponse res{http::status::not_modified, call.header.version()};
    res.set(http::field::etag, etag);
    return res;
  }
  return file_response(call.header.method(), path, media_type, etag, call.header.version());
}

}  // namespace texwarp::server
