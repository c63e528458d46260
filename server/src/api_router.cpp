// The HTTP routes of texwarpd: see api_router.hpp.
#include "texwarp/server/api_router.hpp"

#include <openssl/crypto.h>

#include <algorithm>
#include <charconv>
#include <vector>

#include "texwarp/proto/blob_info.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/server/embedded_documents.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/request_target.hpp"

namespace texwarp::server {
namespace {

constexpr std::uint64_t kSmallBodyLimit = 64 << 10;  // routes that take no body
constexpr int kDefaultPageSize = 50;
constexpr int kMaxPageSize = 500;
constexpr std::size_t kMaxIdempotencyKeyLength = 255;

std::string path_only(std::string_view target) { return std::string(target.substr(0, target.find('?'))); }

// The route pattern for a target (metrics label) and the methods it allows; empty pattern: no such route.
struct RouteMatch {
  std::string pattern;
  std::vector<http::verb> methods;
};

RouteMatch match_route(const RequestTarget& t) {
  const auto& s = t.segments;
  using V = http::verb;
  if (s.size() == 1 && s[0] == "livez") return {"/livez", {V::get, V::head}};
  if (s.size() == 1 && s[0] == "readyz") return {"/readyz", {V::get, V::head}};
  if (s.size() == 1 && s[0] == "metrics") return {"/metrics", {V::get}};
  if (s.empty() || s[0] != "v1") return {};
  if (s.size() == 2 && s[1] == "openapi.json") return {"/v1/openapi.json", {V::get}};
  if (s.size() == 3 && s[1] == "schemas") return {"/v1/schemas/{name}", {V::get}};
  if (s.size() == 2 && s[1] == "blobs") return {"/v1/blobs", {V::post}};
  if (s.size() == 3 && s[1] == "blobs") return {"/v1/blobs/{id}", {V::get, V::head}};
  if (s.size() == 2 && s[1] == "jobs") return {"/v1/jobs", {V::post, V::get}};
  if (s.size() == 3 && s[1] == "jobs") return {"/v1/jobs/{id}", {V::get, V::delete_}};
  if (s.size() == 4 && s[1] == "jobs" && s[3] == "result") return {"/v1/jobs/{id}/result", {V::get}};
  if (s.size() == 5 && s[1] == "jobs" && s[3] == "files") return {"/v1/jobs/{id}/files/{name}", {V::get, V::head}};
  return {};
}

std::string allow_header(const std::vector<http::verb>& methods) {
  std::string out;
  for (auto m : methods) {
    if (!out.empty()) out += ", ";
    out += std::string(http::to_string(m));
  }
  return out;
}

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
  for (const auto& [k, v] : t.query) {
    if (std::none_of(known.begin(), known.end(), [&](const char* n) { return k == n; })) {
      throw ApiError(400, "bad-query", "Bad query parameter", "unknown query parameter \"" + proto::utf8_prefix(k, 40) + "\"",
                     "?" + proto::utf8_prefix(k, 40));
    }
  }
}

}  // namespace

unsigned response_status(const ApiResponse& response) {
  return std::visit([](const auto& r) { return r.result_int(); }, response);
}

ApiRouter::ApiRouter(const ServerConfig& config, JobService& service, Metrics& metrics)
    : config_(config), service_(service), metrics_(metrics) {}

StringResponse ApiRouter::problem(const ApiError& error, const std::string& instance, unsigned version,
                                  const std::string& request_id) const {
  StringResponse res{static_cast<http::status>(error.status()), version};
  res.set(http::field::content_type, "application/problem+json");
  res.set(http::field::cache_control, "no-store");
  if (!request_id.empty()) res.set("X-Request-Id", request_id);
  if (error.retry_after_s()) res.set(http::field::retry_after, std::to_string(*error.retry_after_s()));
  for (const auto& [name, value] : error.headers()) res.set(name, value);
  if (error.status() == 401) res.set(http::field::www_authenticate, "Bearer realm=\"texwarpd\"");
  res.body() = proto::safe_dump(proto::encode_problem(error.problem(instance))) + "\n";
  res.prepare_payload();
  return res;
}

RequestPlan ApiRouter::plan(const RequestHeader& header) {
  RequestPlan plan;
  plan.body_limit = kSmallBodyLimit;
  const RequestTarget target = parse_request_target(header.target());
  const RouteMatch route = match_route(target);
  const bool open_route = route.pattern == "/livez" || route.pattern == "/readyz";
  if (!route.pattern.empty()) plan.route = route.pattern;
  // Authentication comes first: without a valid token nothing but the probes says anything, not even "no route".
  if (!config_.token.empty() && !open_route) {
    const auto credentials = bearer_credentials(header[http::field::authorization]);
    if (!credentials || !token_matches(*credentials, config_.token)) {
      plan.refusal = ApiError(401, "unauthorized", "Unauthorized",
                              credentials ? "the bearer token is not valid for this server"
                                          : "this server requires `Authorization: Bearer <token>`");
      return plan;
    }
  }
  if (route.pattern.empty()) {
    plan.refusal = ApiError(404, "not-found", "Not found",
                            "no route " + proto::utf8_prefix(path_only(header.target()), 120) +
                                " (see GET /v1/openapi.json for the API)");
    return plan;
  }
  if (std::find(route.methods.begin(), route.methods.end(), header.method()) == route.methods.end()) {
    plan.refusal = ApiError(405, "method-not-allowed", "Method not allowed",
                            std::string(header.method_string()) + " is not allowed on " + route.pattern + "; use " +
                                allow_header(route.methods))
                       .header("Allow", allow_header(route.methods));
    return plan;
  }
  if (header.method() == http::verb::post) {
    plan.body_limit = route.pattern == "/v1/blobs" ? config_.max_blob_bytes : config_.max_job_body_bytes;
    plan.off_io_thread = true;
    if (route.pattern == "/v1/blobs") {
      if (const std::string type = media_type(header[http::field::content_type]); type.rfind("multipart/", 0) == 0) {
        plan.refusal = ApiError(415, "unsupported-media-type", "Unsupported media type",
                                "POST /v1/blobs takes the file's bytes as they are, not a form (got \"" +
                                    proto::utf8_prefix(type, 60) +
                                    "\"); send e.g. `curl --data-binary @x.png -H 'Content-Type: "
                                    "application/octet-stream' <server>/v1/blobs`");
        return plan;
      }
      plan.body = RequestPlan::Body::kFile;
      plan.upload_file = service_.blobs().temp_path();
    } else if (!is_json_media_type(header[http::field::content_type])) {
      plan.refusal = ApiError(415, "unsupported-media-type", "Unsupported media type",
                              "send the job as JSON with `Content-Type: application/json` (got \"" +
                                  proto::utf8_prefix(header[http::field::content_type], 60) + "\")");
      return plan;
    }
  }
  const auto length = header[http::field::content_length];
  if (!length.empty()) {
    std::uint64_t n = 0;
    const auto [end, ec] = std::from_chars(length.data(), length.data() + length.size(), n);
    if (ec == std::errc() && end == length.data() + length.size() && n > plan.body_limit) {
      plan.refusal = ApiError(413, "body-too-large", "Request body too large",
                              "the body has " + std::to_string(n) + " bytes; this route accepts at most " +
                                  std::to_string(plan.body_limit) +
                                  (route.pattern == "/v1/jobs" ? " (upload large images with POST /v1/blobs and refer to them by id)" : ""));
      return plan;
    }
  }
  if (route.pattern == "/v1/jobs" && header.method() == http::verb::post) {
    const auto key = header["Idempotency-Key"];
    if (!key.empty()) {
      const bool printable = std::all_of(key.begin(), key.end(), [](char c) { return c > 0x20 && c < 0x7f; });
      if (key.size() > kMaxIdempotencyKeyLength || !printable) {
        plan.refusal = ApiError(400, "bad-idempotency-key", "Bad Idempotency-Key",
                                "Idempotency-Key must be 1 to 255 visible ASCII characters (a UUID is a good choice)");
        return plan;
      }
      try {
        plan.idempotency_claim = service_.claim_idempotency_key(std::string(key));
      } catch (const ApiError& e) {
        plan.refusal = e;
      }
    }
  }
  return plan;
}

ApiResponse ApiRouter::handle(const RequestHeader& header, const std::string& body, RequestPlan& plan,
                              const std::string& request_id) {
  const std::string instance = path_only(header.target());
  ApiResponse response = [&]() -> ApiResponse {
    try {
      if (plan.refusal) return problem(*plan.refusal, instance, header.version(), request_id);
      return dispatch(header, body, plan);
    } catch (const ApiError& e) {
      return problem(e, instance, header.version(), request_id);
    } catch (const std::exception& e) {
      log_event(LogLevel::kError, "internal error", {{"request_id", request_id}, {"route", plan.route}, {"error", e.what()}});
      return problem(ApiError(500, "internal", "Internal server error",
                              "the server could not answer this request; quote request id " + request_id +
                                  " when reporting it"),
                     instance, header.version(), request_id);
    }
  }();
  std::visit([&](auto& r) { r.set("X-Request-Id", request_id); }, response);
  if (header.method() == http::verb::head) {  // the same header, never a body
    if (auto* full = std::get_if<StringResponse>(&response)) {
      EmptyResponse head{full->result(), full->version()};
      for (const auto& field : *full) head.set(field.name_string(), field.value());
      head.content_length(full->body().size());
      return head;
    }
  }
  return response;
}

ApiResponse ApiRouter::dispatch(const RequestHeader& header, const std::string& body, RequestPlan& plan) {
  const RequestTarget t = parse_request_target(header.target());
  const unsigned version = header.version();
  const std::string& route = plan.route;
  const http::verb method = header.method();

  if (route == "/livez") return json_response(http::status::ok, {{"status", "ok"}}, version);
  if (route == "/readyz") {
    const Readiness r = service_.readiness();
    nlohmann::json j = {{"status", r.status}, {"checks", r.checks}};
    auto res = json_response(r.ready ? http::status::ok : http::status::service_unavailable, j, version);
    if (!r.ready) res.set(http::field::retry_after, "5");
    return res;
  }
  if (route == "/metrics") {
    return text_response(http::status::ok, metrics_.render(service_.gauges()), "text/plain; version=0.0.4; charset=utf-8",
                         version);
  }
  if (route == "/v1/openapi.json" || route == "/v1/schemas/{name}") {
    const std::string name = route == "/v1/openapi.json" ? "openapi.json" : t.segments[2];
    const auto doc = embedded_document(name);
    if (!doc) {
      throw ApiError(404, "not-found", "Not found", "no schema \"" + proto::utf8_prefix(name, 60) + "\" (see GET /v1/openapi.json)");
    }
    auto res = text_response(http::status::ok, std::string(*doc), "application/json", version);
    res.set(http::field::cache_control, "max-age=300");
    return res;
  }
  if (route == "/v1/blobs") {
    proto::BlobInfo info;
    try {
      info = service_.adopt_blob(plan.upload_file);
    } catch (const std::filesystem::filesystem_error& e) {
      if (e.code() == std::errc::no_space_on_device || e.code() == std::errc::file_too_large) {
        throw storage_full_error("the upload");
      }
      throw;
    }
    log_event(LogLevel::kDebug, "blob stored", {{"blob", info.id}, {"bytes", info.bytes}, {"created", info.created}});
    auto res = json_response(info.created ? http::status::created : http::status::ok, proto::encode_blob_info(info), version);
    res.set(http::field::location, "/v1/blobs/" + info.id);
    return res;
  }
  if (route == "/v1/blobs/{id}") {
    const std::string& id = t.segments[2];
    if (!proto::is_blob_id(id) || !service_.blobs().contains(id)) {
      throw ApiError(404, "not-found", "No such blob", "there is no blob \"" + proto::utf8_prefix(id, 80) + "\" on this server");
    }
    const auto size = service_.blobs().size(id).value_or(0);
    if (method == http::verb::head) {
      EmptyResponse res{http::status::ok, version};
      res.set(http::field::content_type, "application/octet-stream");
      res.content_length(size);
      return res;
    }
    FileResponse res{http::status::ok, version};
    boost::beast::error_code ec;
    res.body().open(service_.blobs().path_of(id).c_str(), boost::beast::file_mode::scan, ec);
    if (ec) throw std::runtime_error("cannot open blob " + id + ": " + ec.message());
    res.set(http::field::content_type, "application/octet-stream");
    res.set(http::field::etag, "\"" + id.substr(7) + "\"");
    res.prepare_payload();
    return res;
  }
  if (route == "/v1/jobs" && method == http::verb::post) {
    reject_unknown_query(t, {});
    const auto key = header["Idempotency-Key"];
    const SubmitResult r = service_.submit(body, key.empty() ? std::nullopt : std::optional<std::string>(key));
    auto res = json_response(http::status::accepted, proto::encode_job_status(r.status), version);
    res.set(http::field::location, "/v1/jobs/" + r.status.id);
    if (r.replayed) res.set("Idempotent-Replayed", "true");
    return res;
  }
  if (route == "/v1/jobs") {
    reject_unknown_query(t, {"limit", "cursor", "state"});
    int limit = kDefaultPageSize;
    if (const std::string v = query_value(t, "limit"); !v.empty()) {
      const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), limit);
      if (ec != std::errc() || end != v.data() + v.size() || limit < 1 || limit > kMaxPageSize) {
        throw ApiError(400, "bad-query", "Bad query parameter",
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
        throw ApiError(400, "bad-query", "Bad query parameter", e.what(), "?state");
      }
    }
    return json_response(http::status::ok, proto::encode_job_page(service_.list(query_value(t, "cursor"), limit, state)),
                         version);
  }
  const std::string id = t.segments.size() > 2 ? t.segments[2] : std::string();
  if (route == "/v1/jobs/{id}" && method == http::verb::delete_) {
    const CancelResult r = service_.cancel(id);
    return json_response(r.requested ? http::status::accepted : http::status::ok, proto::encode_job_status(r.status),
                         version);
  }
  if (route == "/v1/jobs/{id}") {
    return json_response(http::status::ok, proto::encode_job_status(service_.status(id)), version);
  }
  if (route == "/v1/jobs/{id}/result") {
    return json_response(http::status::ok, proto::encode_job_result(service_.result(id)), version);
  }
  if (route == "/v1/jobs/{id}/files/{name}") {
    std::string media_type;
    std::string sha256;
    const auto path = service_.result_file(id, t.segments[4], &media_type, &sha256);
    const std::string etag = "\"" + sha256 + "\"";
    if (header[http::field::if_none_match] == etag) {
      EmptyResponse res{http::status::not_modified, version};
      res.set(http::field::etag, etag);
      return res;
    }
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
    if (ec) throw std::runtime_error("cannot open result file " + path.string() + ": " + ec.message());
    res.set(http::field::content_type, media_type);
    res.set(http::field::etag, etag);
    res.prepare_payload();
    return res;
  }
  throw ApiError(404, "not-found", "Not found", "no route " + proto::utf8_prefix(path_only(header.target()), 120));
}

}  // namespace texwarp::server
