// libtexwarp_client's calls: requests, retries within a time budget, waiting and fetching: see client.hpp.
#include "texwarp/client/client.hpp"

#include <fcntl.h>
#include <strings.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <optional>
#include <random>
#include <thread>

#include "http_connection.hpp"
#include "stop_state.hpp"
#include "texwarp/proto/blob_info_codec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_batch_codec.hpp"
#include "texwarp/proto/job_labels.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/node_status_codec.hpp"
#include "texwarp/proto/problem_details_codec.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp::client {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

ClientError make_error(ErrorCode code, std::string message) {
  return ClientError{code, 0, std::move(message), std::nullopt, std::nullopt};
}

std::mt19937_64& random_engine() {
  thread_local std::mt19937_64 rng(std::random_device{}() ^ (static_cast<std::uint64_t>(std::random_device{}()) << 32));
  return rng;
}

// A uniform fraction in [0, 1).
double random_fraction() { return std::uniform_real_distribution<double>(0.0, 1.0)(random_engine()); }

std::string random_hex(int bytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (int i = 0; i < bytes; ++i) {
    const auto v = random_engine()();
    out.push_back(kHex[(v >> 4) & 15]);
    out.push_back(kHex[v & 15]);
  }
  return out;
}

// Seconds from a Retry-After value (delta-seconds or an HTTP date), if it parses.
std::optional<double> retry_after_seconds(const std::string& value) {
  if (value.empty()) return std::nullopt;
  if (std::all_of(value.begin(), value.end(), [](char c) { return c >= '0' && c <= '9'; }) && value.size() < 10) {
    return std::stod(value);
  }
  std::tm tm{};
  if (strptime(value.c_str(), "%a, %d %b %Y %H:%M:%S GMT", &tm) == nullptr) return std::nullopt;
  const double delta = std::difftime(timegm(&tm), std::time(nullptr));
  return std::max(0.0, delta);
}

// Whether a request may be sent again after it might have reached the server: reads, DELETE and PUT, uploads
// (content-addressed: the same bytes make the same blob) and anything carrying an Idempotency-Key.
bool safe_to_resend(const HttpRequest& request) {
  if (request.method == "GET" || request.method == "HEAD" || request.method == "DELETE" || request.method == "PUT") {
    return true;
  }
  if (request.target == "/v1/blobs") return true;
  return std::any_of(request.headers.begin(), request.headers.end(), [](const auto& header) {
    return header.first.size() == 15 && strncasecmp(header.first.c_str(), "Idempotency-Key", 15) == 0;
  });
}

// An answer that says "not now" rather than "no": 429, 502/503/504 (a proxy's 502/504 only for requests safe to
// resend, since the server behind it may have taken them; 503 unless the caller reads it as an answer), and 409
// "a request with this Idempotency-Key is in progress".
bool retryable_answer(const HttpReply& reply, bool safe, bool retry_unavailable) {
  switch (reply.status) {
    case 429:
      return true;
    case 503:
      return retry_unavailable;
    case 502:
    case 504:
      return safe;
    case 409:
      return reply.body.find("idempotency-key-in-use") != std::string::npos;
    default:
      return false;
  }
}

// A failure that another try may cure: a connection refused, reset or timed out, or a "not now" answer.
bool transient(const ClientError& e) {
  if (e.code == ErrorCode::kConnection || e.code == ErrorCode::kTimeout) return true;
  return e.code == ErrorCode::kHttp &&
         (e.http_status == 429 || e.http_status == 502 || e.http_status == 503 || e.http_status == 504);
}

// `t` + `d`, with d cut to ten years so that no setting overflows the clock.
Clock::time_point later(Clock::time_point t, std::chrono::milliseconds d) {
  return t + std::min(d, std::chrono::milliseconds(std::chrono::hours(24 * 365 * 10)));
}

std::string seconds_text(Clock::duration d) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f s", std::chrono::duration<double>(d).count());
  return text;
}

// The error of a non-2xx reply, with the server's problem document when it sent one.
ClientError http_error(const HttpReply& reply, const std::string& what) {
  ClientError e;
  e.code = ErrorCode::kHttp;
  e.http_status = reply.status;
  try {
    const auto j = nlohmann::json::parse(reply.body);
    if (j.is_object()) e.problem = proto::decode_problem(j);
  } catch (const std::exception&) {
  }
  std::string text = what + ": HTTP " + std::to_string(reply.status);
  if (e.problem) {
    if (!e.problem->title.empty()) text += " " + e.problem->title;
    if (!e.problem->detail.empty()) text += ": " + e.problem->detail;
  }
  e.message = text;
  return e;
}

template <typename T, typename Decode>
Result<T> decode_reply(const HttpReply& reply, const std::string& what, Decode&& decode) {
  try {
    return decode(nlohmann::json::parse(reply.body));
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kProtocol, what + ": unexpected answer from the server: " + e.what());
  }
}

// Runs f, turning any exception into a ClientError (nothing escapes the library).
template <typename T, typename F>
Result<T> guarded(F&& f) {
  try {
    return f();
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kInternal, std::string("libtexwarp_client: ") + e.what());
  } catch (...) {
    return make_error(ErrorCode::kInternal, "libtexwarp_client: unknown error");
  }
}

std::optional<ClientError> fsync_and_rename(const fs::path& temp, const fs::path& target) {
  const int fd = ::open(temp.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || ::fsync(fd) != 0) {
    if (fd >= 0) ::close(fd);
    return make_error(ErrorCode::kIo, "cannot sync " + temp.string());
  }
  ::close(fd);
  std::error_code ec;
  fs::rename(temp, target, ec);
  if (ec) return make_error(ErrorCode::kIo, "cannot write " + target.string() + ": " + ec.message());
  const int dir =
      ::open(target.parent_path().empty() ? "." : target.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
  return std::nullopt;
}

bool safe_file_name(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
         name.find('\\') == std::string::npos && name.find('\0') == std::string::npos;
}

// A job id that can go into a request path as it is: [A-Za-z0-9_.-], at most 128 characters, not "." or "..".
bool safe_job_id(const std::string& id) {
  return safe_file_name(id) && id.size() <= 128 && std::all_of(id.begin(), id.end(), [](char c) {
           return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
                  c == '-';
         });
}

ClientError not_a_job_id(const std::string& id) {
  return make_error(ErrorCode::kInvalidArgument, "not a job id: \"" + id + "\"");
}

// A query component or path segment: every byte but A-Z a-z 0-9 - . _ ~ percent-encoded (so "&", "=", "+", "#",
// "?", spaces and UTF-8 in a label's value or a file name arrive as they were).
std::string url_escape(std::string_view text) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '.' ||
        c == '_' || c == '~') {
      out.push_back(ch);
    } else {
      out.push_back('%');
      out.push_back(kHex[c >> 4]);
      out.push_back(kHex[c & 15]);
    }
  }
  return out;
}

// The job of a batch a problem's path names: "$.jobs[3]…" (the codec's JSON path) or "/jobs/3…" (a JSON pointer).
std::optional<std::size_t> batch_index_of(const std::string& path) {
  std::size_t at = 0;
  char close = 0;
  if (path.rfind("$.jobs[", 0) == 0) {
    at = 7;
    close = ']';
  } else if (path.rfind("/jobs/", 0) == 0) {
    at = 6;
    close = '/';
  } else {
    return std::nullopt;
  }
  std::size_t end = at;
  while (end < path.size() && end - at < 9 && path[end] >= '0' && path[end] <= '9') ++end;
  if (end == at || (end < path.size() && path[end] != close) || (end == path.size() && close == ']')) {
    return std::nullopt;
  }
  return static_cast<std::size_t>(std::stoul(path.substr(at, end - at)));
}

// Sleeps `pause`, or less when `stop` is requested meanwhile (then false).
bool pause_unless_stopped(std::chrono::milliseconds pause, const std::stop_token& stop) {
  if (!stop.stop_possible()) {
    std::this_thread::sleep_for(pause);
    return true;
  }
  std::mutex m;
  std::condition_variable_any cv;
  std::unique_lock lock(m);
  return !cv.wait_for(lock, stop, pause, [] { return false; }) && !stop.stop_requested();
}

ClientError stopped_error(const std::string& what) {
  return make_error(ErrorCode::kStopped, what + ": stopped (WaitOptions::stop was requested)");
}

// Idle keep-alive connections kept for the next calls; more in use at once are opened, then closed after use.
constexpr std::size_t kMaxIdleConnections = 8;

}  // namespace

struct Client::Impl {
  ClientOptions options;
  std::optional<ClientError> options_error;  // a bad server URL or retry setting: every call returns it
  std::string host;
  std::string port;
  std::mutex pool_mutex;
  std::vector<std::unique_ptr<HttpConnection>> idle;  // guarded by pool_mutex

  // A connection for one call (with its retries): an idle one, else a new one.
  std::unique_ptr<HttpConnection> borrow() {
    {
      std::lock_guard lock(pool_mutex);
      if (!idle.empty()) {
        auto connection = std::move(idle.back());
        idle.pop_back();
        return connection;
      }
    }
    return std::make_unique<HttpConnection>(host, port, options.connect_timeout, options.request_timeout,
                                            options.user_agent);
  }
  void give_back(std::unique_ptr<HttpConnection> connection) {
    std::lock_guard lock(pool_mutex);
    if (idle.size() < kMaxIdleConnections) idle.push_back(std::move(connection));
  }

  explicit Impl(ClientOptions o) : options(std::move(o)) {
    if (options.retry_budget.count() < 0 || options.initial_backoff.count() < 0 ||
        options.max_retry_delay.count() <= 0) {
      options_error = make_error(ErrorCode::kInvalidArgument,
                                 "ClientOptions: retry_budget and initial_backoff must not be negative, "
                                 "max_retry_delay must be positive");
      return;
    }
    options.initial_backoff = std::min(options.initial_backoff, options.max_retry_delay);
    std::string s = options.server;
    if (s.rfind("https://", 0) == 0) {
      options_error =
          make_error(ErrorCode::kInvalidArgument,
                     "https is not supported by libtexwarp_client: use http:// (loopback, or a TLS proxy in front)");
      return;
    }
    if (s.rfind("http://", 0) == 0) s = s.substr(7);
    while (!s.empty() && s.back() == '/') s.pop_back();
    if (s.empty() || s.find('/') != std::string::npos) {
      options_error = make_error(ErrorCode::kInvalidArgument,
                                 "server URL must be http://HOST[:PORT], got \"" + options.server + "\"");
      return;
    }
    std::string url_host = s;
    std::string url_port = "80";
    if (s.front() == '[') {  // [v6 address]:port
      const auto close = s.find(']');
      url_host = close == std::string::npos ? std::string() : s.substr(1, close - 1);
      const std::string rest = close == std::string::npos ? std::string() : s.substr(close + 1);
      if (!rest.empty()) url_port = rest[0] == ':' ? rest.substr(1) : std::string();
    } else if (const auto colon = s.rfind(':'); colon != std::string::npos) {
      url_host = s.substr(0, colon);
      url_port = s.substr(colon + 1);
    }
    if (url_host.empty() || url_port.empty() ||
        !std::all_of(url_port.begin(), url_port.end(), [](char c) { return c >= '0' && c <= '9'; })) {
      options_error = make_error(ErrorCode::kInvalidArgument,
                                 "server URL must be http://HOST[:PORT], got \"" + options.server + "\"");
      return;
    }
    host = url_host;
    port = url_port;
  }

  // The pause before the next try without a Retry-After: `backoff` lengthened by up to half at random, so that
  // clients turned away together do not come back together; at the cap, between ¾ of it and all of it.
  std::chrono::milliseconds jittered(std::chrono::milliseconds backoff) const {
    const double ms = static_cast<double>(backoff.count()) * (1.0 + 0.5 * random_fraction());
    const auto cap = static_cast<double>(options.max_retry_delay.count());
    return std::chrono::milliseconds(static_cast<long long>(ms <= cap ? ms : cap * (0.75 + 0.25 * random_fraction())));
  }

  // One call with its retries (see ClientOptions): until an answer that is not "not now", the retry budget is
  // spent, or `deadline` (wait()'s timeout) passes. A Retry-After is waited for as given when it fits before the
  // end; otherwise its answer is returned at once (a busy server is not asked again sooner than it said).
  // `retry_unavailable` false: 503 is an answer. A requested `stop` ends it (kStopped) at once, even mid-request.
  Result<HttpReply> call(HttpRequest request, bool retry_unavailable = true,
                         std::optional<Clock::time_point> deadline = std::nullopt, const std::stop_token& stop = {}) {
    if (options_error) return *options_error;
    if (stop.stop_requested()) return stopped_error(request.method + " " + request.target);
    std::unique_ptr<HttpConnection> connection = borrow();
    Result<HttpReply> r = call_on(*connection, std::move(request), retry_unavailable, deadline, stop);
    // A connection whose exchange was abandoned is in an unknown state: it is not kept.
    if (r.ok() || r.error().code != ErrorCode::kStopped) give_back(std::move(connection));
    return r;
  }

  Result<HttpReply> call_on(HttpConnection& connection, HttpRequest request, bool retry_unavailable,
                            std::optional<Clock::time_point> deadline, const std::stop_token& stop) const {
    if (!options.token.empty()) request.headers.emplace_back("Authorization", "Bearer " + options.token);
    const bool safe = safe_to_resend(request);
    const auto start = Clock::now();
    const auto budget_end = later(start, options.retry_budget);
    const auto end = deadline ? std::min(*deadline, budget_end) : budget_end;
    auto backoff = std::max(options.initial_backoff, std::chrono::milliseconds(1));
    for (int retries = 0;; ++retries) {
      Result<HttpReply> r = connection.exchange(request, stop);
      std::optional<double> asked_s;  // the server's Retry-After
      if (!r.ok()) {
        if (r.error().code == ErrorCode::kStopped) return r;
        // A request that is not safe to resend is only retried when the server said it did not take it.
        if (!safe || (r.error().code != ErrorCode::kConnection && r.error().code != ErrorCode::kTimeout)) return r;
      } else {
        if (!retryable_answer(r.value(), safe, retry_unavailable)) return r;
        const auto it = r.value().headers.find("retry-after");
        if (it != r.value().headers.end()) asked_s = retry_after_seconds(it->second);
      }
      const auto now = Clock::now();
      if (now >= end || (options.max_retries >= 0 && retries >= options.max_retries)) {
        return gave_up(std::move(r), retries, now - start);
      }
      std::chrono::milliseconds pause;
      if (asked_s) {  // as asked, up to a tenth later (clients told the same do not all come back at once)
        const auto asked = std::chrono::duration_cast<std::chrono::milliseconds>(
            std::chrono::duration<double>(std::min(*asked_s, 1e9) * (1.0 + 0.1 * random_fraction())));
        if (now + asked > end) return gave_up(std::move(r), retries, now - start);  // it wants more than is left
        pause = asked;
      } else {
        pause = std::min(jittered(backoff), std::chrono::duration_cast<std::chrono::milliseconds>(end - now) +
                                                std::chrono::milliseconds(1));  // the last try at the budget's end
        backoff = backoff > options.max_retry_delay / 2 ? options.max_retry_delay : backoff * 2;
      }
      if (!pause_unless_stopped(pause, stop)) return stopped_error(request.method + " " + request.target);
    }
  }

  // The last result of a call that stops retrying; a transport error says how long it was retried.
  static Result<HttpReply> gave_up(Result<HttpReply> r, int retries, Clock::duration spent) {
    if (r.ok() || retries == 0) return r;
    ClientError e = r.error();
    e.message += " (gave up after " + std::to_string(retries + 1) + " attempts in " + seconds_text(spent) + ")";
    return e;
  }

  // GET /v1/jobs/{id}; with wait_s > 0 a long-poll (?wait=wait_s).
  Result<proto::JobStatus> status(const std::string& job_id, std::optional<Clock::time_point> deadline = std::nullopt,
                                  int wait_s = 0, const std::stop_token& stop = {}) {
    if (!safe_job_id(job_id)) return not_a_job_id(job_id);
    HttpRequest req;
    req.target = "/v1/jobs/" + job_id;
    if (wait_s > 0) req.target += "?wait=" + std::to_string(wait_s);
    return job_call(std::move(req), "status of " + job_id, 200, 200, deadline, stop);
  }

  // DELETE /v1/jobs/{id}, answered as it is (purge() reads 200, 202, 204, 404 and 409 each its way).
  Result<HttpReply> remove(const std::string& job_id) {
    HttpRequest req;
    req.method = "DELETE";
    req.target = "/v1/jobs/" + job_id;
    return call(std::move(req));
  }

  Result<proto::JobStatus> job_call(HttpRequest request, const std::string& what, int ok_status_a, int ok_status_b,
                                    std::optional<Clock::time_point> deadline = std::nullopt,
                                    const std::stop_token& stop = {}) {
    Result<HttpReply> r = call(std::move(request), true, deadline, stop);
    if (!r.ok()) return r.error();
    if (r->status != ok_status_a && r->status != ok_status_b) return http_error(r.value(), what);
    return decode_reply<proto::JobStatus>(r.value(), what,
                                          [](const nlohmann::json& j) { return proto::decode_job_status(j); });
  }

  static Result<proto::BlobInfo> blob_reply(Result<HttpReply> r) {
    if (!r.ok()) return r.error();
    if (r->status != 200 && r->status != 201) return http_error(r.value(), "upload");
    return decode_reply<proto::BlobInfo>(r.value(), "upload",
                                         [](const nlohmann::json& j) { return proto::decode_blob_info(j); });
  }
};

Client::Client(ClientOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}
Client::~Client() = default;
Client::Client(Client&&) noexcept = default;
Client& Client::operator=(Client&&) noexcept = default;

const ClientOptions& Client::options() const { return impl_->options; }

Result<proto::BlobInfo> Client::upload(std::string_view bytes) {
  return guarded<proto::BlobInfo>([&]() -> Result<proto::BlobInfo> {
    HttpRequest req;
    req.method = "POST";
    req.target = "/v1/blobs";
    req.content_type = "application/octet-stream";
    req.body = std::string(bytes);
    return Impl::blob_reply(impl_->call(std::move(req)));
  });
}

Result<proto::BlobInfo> Client::upload_file(const std::string& path) {
  return guarded<proto::BlobInfo>([&]() -> Result<proto::BlobInfo> {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return make_error(ErrorCode::kInvalidArgument, path + ": no such file");
    HttpRequest req;
    req.method = "POST";
    req.target = "/v1/blobs";
    req.content_type = "application/octet-stream";
    req.body_file = path;
    return Impl::blob_reply(impl_->call(std::move(req)));
  });
}

Result<proto::JobStatus> Client::submit(const proto::JobSpec& job, const std::string& idempotency_key) {
  return guarded<proto::JobStatus>(
      [&]() -> Result<proto::JobStatus> { return submit_json(proto::encode_job_spec(job).dump(), idempotency_key); });
}

Result<proto::JobStatus> Client::submit_json(const std::string& job_json, const std::string& idempotency_key) {
  return guarded<proto::JobStatus>([&]() -> Result<proto::JobStatus> {
    HttpRequest req;
    req.method = "POST";
    req.target = "/v1/jobs";
    req.content_type = "application/json";
    req.body = job_json;
    req.headers.emplace_back("Idempotency-Key", idempotency_key.empty() ? random_hex(16) : idempotency_key);
    return impl_->job_call(std::move(req), "submit", 202, 202);
  });
}

Result<std::vector<proto::JobStatus>> Client::submit_batch(const std::vector<proto::JobSpec>& jobs,
                                                           const std::string& idempotency_key) {
  return guarded<std::vector<proto::JobStatus>>([&]() -> Result<std::vector<proto::JobStatus>> {
    if (jobs.empty() || jobs.size() > proto::kMaxBatchJobs) {
      return make_error(ErrorCode::kInvalidArgument, "submit_batch: a batch holds 1 to " +
                                                         std::to_string(proto::kMaxBatchJobs) + " jobs, got " +
                                                         std::to_string(jobs.size()));
    }
    HttpRequest req;
    req.method = "POST";
    req.target = "/v1/jobs:batch";
    req.content_type = "application/json";
    req.body = proto::encode_job_batch(proto::JobBatch{jobs}).dump();
    req.headers.emplace_back("Idempotency-Key", idempotency_key.empty() ? random_hex(16) : idempotency_key);
    Result<HttpReply> r = impl_->call(std::move(req));
    if (!r.ok()) return r.error();
    if (r->status != 201) {
      ClientError e = http_error(r.value(), "submit_batch");
      if (e.problem) e.batch_index = batch_index_of(e.problem->path);
      if (e.batch_index) {
        e.message = "submit_batch: job " + std::to_string(*e.batch_index) + " of " + std::to_string(jobs.size()) +
                    " refused, nothing was submitted: " + e.message.substr(std::string("submit_batch: ").size());
      }
      return e;
    }
    Result<proto::JobBatchStatus> answer = decode_reply<proto::JobBatchStatus>(
        r.value(), "submit_batch", [](const nlohmann::json& j) { return proto::decode_job_batch_status(j); });
    if (!answer.ok()) return answer.error();
    if (answer->jobs.size() != jobs.size()) {
      return make_error(ErrorCode::kProtocol, "submit_batch: sent " + std::to_string(jobs.size()) +
                                                  " jobs, the server answered with " +
                                                  std::to_string(answer->jobs.size()) + " statuses");
    }
    return std::move(answer->jobs);
  });
}

Result<proto::JobStatus> Client::status(const std::string& job_id) {
  return guarded<proto::JobStatus>([&]() -> Result<proto::JobStatus> { return impl_->status(job_id); });
}

Result<proto::JobPage> Client::list(const ListOptions& options) {
  return guarded<proto::JobPage>([&]() -> Result<proto::JobPage> {
    if (options.labels.size() > proto::kMaxJobLabels) {
      return make_error(ErrorCode::kInvalidArgument, "list: at most " + std::to_string(proto::kMaxJobLabels) +
                                                         " label filters, got " +
                                                         std::to_string(options.labels.size()));
    }
    HttpRequest req;
    req.target = "/v1/jobs?limit=" + std::to_string(options.limit);
    if (!options.cursor.empty()) req.target += "&cursor=" + url_escape(options.cursor);
    if (options.state) req.target += std::string("&state=") + proto::to_string(*options.state);
    for (const auto& [key, value] : options.labels) {
      try {
        const auto at = proto::InputLocation::flag("label " + key);
        proto::check_job_label(key, value, at, at);
      } catch (const InputError& e) {
        return make_error(ErrorCode::kInvalidArgument, std::string("list: ") + e.what());
      }
      std::string label = key;
      label.append("=").append(value);
      req.target.append("&label=").append(url_escape(label));
    }
    Result<HttpReply> r = impl_->call(std::move(req));
    if (!r.ok()) return r.error();
    if (r->status != 200) return http_error(r.value(), "list");
    return decode_reply<proto::JobPage>(r.value(), "list",
                                        [](const nlohmann::json& j) { return proto::decode_job_page(j); });
  });
}

Result<proto::JobStatus> Client::wait(const std::string& job_id, const WaitOptions& options) {
  return guarded<proto::JobStatus>([&]() -> Result<proto::JobStatus> {
    using std::chrono::duration_cast;
    using std::chrono::milliseconds;
    using std::chrono::seconds;
    const auto start = Clock::now();
    std::optional<Clock::time_point> deadline;
    if (options.timeout.count() > 0) deadline = later(start, options.timeout);
    // The longest long-poll: kMaxLongPollS, and half the request timeout (the answer must come within it).
    const int longest_s = static_cast<int>(
        std::min<long long>(kMaxLongPollS, duration_cast<seconds>(impl_->options.request_timeout).count() / 2));
    const int progress_s =
        static_cast<int>(std::max<long long>(1, duration_cast<seconds>(options.progress_every).count()));
    bool long_poll = longest_s > 0;  // until the server says it does not know ?wait
    auto interval = std::max(options.poll_min, milliseconds(1));
    int last_progress = -1;
    std::optional<proto::JobState> last_state;
    const std::stop_token stop = StopTokenAccess::std_token(options.stop);
    for (;;) {
      // The first request asks at once (its answer is the job's state now); then long-polls, each at most until
      // the timeout (whole seconds; under a second left: polling).
      int wait_s = 0;
      if (long_poll && last_state) {
        wait_s = longest_s;
        if (deadline) {
          wait_s =
              static_cast<int>(std::min<long long>(wait_s, duration_cast<seconds>(*deadline - Clock::now()).count()));
        }
        // A long-poll answers at a change from the state at its arrival: one between two requests shows at the next.
        if (options.on_progress) wait_s = std::min(wait_s, progress_s);
      }
      const auto asked_at = Clock::now();
      // Each request retries a server that went away (a restart) within the retry budget, but not past the timeout.
      Result<proto::JobStatus> s = impl_->status(job_id, deadline, wait_s, stop);
      if (!s.ok()) {
        if (wait_s > 0 && s.error().code == ErrorCode::kHttp && s.error().http_status == 400) {
          long_poll = false;  // a server older than long-poll: ask again at once, then poll
          continue;
        }
        if (deadline && Clock::now() >= *deadline && transient(s.error())) {
          return make_error(ErrorCode::kTimeout, "job " + job_id +
                                                     ": no answer from the server before the wait timeout (" +
                                                     s.error().message + ")");
        }
        return s;
      }
      const bool changed = s->state != last_state;
      if (options.on_progress && (s->progress != last_progress || changed)) options.on_progress(s.value());
      last_progress = s->progress;
      last_state = s->state;
      if (proto::is_terminal(s->state)) return s;
      // A long-poll answered without a change well before its time: the server does not hold requests (it ignores
      // ?wait); pause as polling does, so that waiting never becomes a busy loop.
      const bool early = wait_s > 0 && !changed && Clock::now() - asked_at < milliseconds(wait_s * 500);
      const bool next_is_long_poll = long_poll && !early && (!deadline || *deadline - Clock::now() >= seconds(1));
      const auto pause = next_is_long_poll ? milliseconds(0) : interval;
      if (deadline && Clock::now() + pause >= *deadline) {
        return make_error(ErrorCode::kTimeout, "job " + job_id + " is still " + proto::to_string(s->state) + " (" +
                                                   std::to_string(s->progress) + "%) after the wait timeout");
      }
      if (pause.count() > 0) {
        if (!pause_unless_stopped(pause, stop)) return stopped_error("wait for " + job_id);
        interval = std::min(milliseconds(interval.count() * 3 / 2 + 1), options.poll_max);
      }
    }
  });
}

Result<proto::JobStatus> Client::cancel(const std::string& job_id) {
  return guarded<proto::JobStatus>([&]() -> Result<proto::JobStatus> {
    if (!safe_job_id(job_id)) return not_a_job_id(job_id);
    // POST …:cancel never purges: a job that finished meanwhile is answered 409 job-finished and keeps its results.
    HttpRequest req;
    req.method = "POST";
    req.target = "/v1/jobs/" + job_id + ":cancel";
    Result<HttpReply> r = impl_->call(std::move(req));
    if (!r.ok()) return r.error();
    if (r->status == 409) {
      ClientError e = http_error(r.value(), "cancel " + job_id);
      if (e.problem && e.problem->type == std::string(proto::kProblemTypePrefix) + "job-finished") {
        e.code = ErrorCode::kWrongState;
      }
      return e;
    }
    if (r->status != 200 && r->status != 202) return http_error(r.value(), "cancel " + job_id);
    return decode_reply<proto::JobStatus>(r.value(), "cancel " + job_id,
                                          [](const nlohmann::json& j) { return proto::decode_job_status(j); });
  });
}

Result<bool> Client::purge(const std::string& job_id) {
  return guarded<bool>([&]() -> Result<bool> {
    if (!safe_job_id(job_id)) return not_a_job_id(job_id);
    // An unfinished job is not sent a DELETE: the server would cancel it. A finished one stays finished.
    Result<proto::JobStatus> now = impl_->status(job_id);
    if (!now.ok()) return now.error();
    if (!proto::is_terminal(now->state)) {
      return make_error(ErrorCode::kWrongState, "purge " + job_id + ": the job is " + proto::to_string(now->state) +
                                                    "; only a finished job can be purged (cancel stops it)");
    }
    Result<HttpReply> r = impl_->remove(job_id);
    if (!r.ok()) return r.error();
    // 404: gone already, by a resend of this DELETE whose first answer was lost, or by another client's purge.
    if (r->status == 204 || r->status == 404) return true;
    if (r->status == 409) {
      ClientError e = http_error(r.value(), "purge " + job_id);
      e.message += " (this server does not purge finished jobs: it is older than DELETE-as-purge)";
      return e;
    }
    if (r->status == 200 || r->status == 202) {
      return make_error(ErrorCode::kProtocol, "purge " + job_id + ": the server answered " + std::to_string(r->status) +
                                                  " (a cancellation) for a finished job");
    }
    return http_error(r.value(), "purge " + job_id);
  });
}

Result<proto::NodeList> Client::nodes() {
  return guarded<proto::NodeList>([&]() -> Result<proto::NodeList> {
    HttpRequest req;
    req.target = "/v1/nodes";
    Result<HttpReply> r = impl_->call(std::move(req));
    if (!r.ok()) return r.error();
    if (r->status != 200) return http_error(r.value(), "nodes");
    return decode_reply<proto::NodeList>(r.value(), "nodes",
                                         [](const nlohmann::json& j) { return proto::decode_node_list(j); });
  });
}

Result<proto::JobResult> Client::result(const std::string& job_id) {
  return guarded<proto::JobResult>([&]() -> Result<proto::JobResult> {
    if (!safe_job_id(job_id)) return not_a_job_id(job_id);
    HttpRequest req;
    req.target = "/v1/jobs/" + job_id + "/result";
    Result<HttpReply> r = impl_->call(std::move(req));
    if (!r.ok()) return r.error();
    if (r->status != 200) return http_error(r.value(), "result of " + job_id);
    return decode_reply<proto::JobResult>(r.value(), "result of " + job_id,
                                          [](const nlohmann::json& j) { return proto::decode_job_result(j); });
  });
}

Result<proto::JobReport> Client::report(const std::string& job_id) {
  Result<proto::JobResult> r = result(job_id);
  if (!r.ok()) return r.error();
  return guarded<proto::JobReport>([&]() -> Result<proto::JobReport> {
    try {
      return proto::decode_job_report(nlohmann::json::parse(r->report_json), JsonPath{"report"});
    } catch (const InputError& e) {
      return make_error(ErrorCode::kProtocol,
                        "report of " + job_id + ": unexpected answer from the server: " + e.what());
    }
  });
}

Result<std::string> Client::fetch_file(const std::string& job_id, const std::string& name) {
  return guarded<std::string>([&]() -> Result<std::string> {
    if (!safe_job_id(job_id) || !safe_file_name(name)) {
      return make_error(ErrorCode::kInvalidArgument,
                        "not a job id and file name: \"" + job_id + "\", \"" + name + "\"");
    }
    HttpRequest req;
    req.target = "/v1/jobs/" + job_id + "/files/" + url_escape(name);
    Result<HttpReply> r = impl_->call(std::move(req));
    if (!r.ok()) return r.error();
    if (r->status != 200) return http_error(r.value(), "fetch " + name);
    return std::move(r.value().body);
  });
}

Result<std::string> Client::fetch_file_to(const std::string& job_id, const std::string& name, const std::string& path) {
  return guarded<std::string>([&]() -> Result<std::string> {
    if (!safe_job_id(job_id) || !safe_file_name(name)) {
      return make_error(ErrorCode::kInvalidArgument,
                        "not a job id and file name: \"" + job_id + "\", \"" + name + "\"");
    }
    const fs::path target(path);
    const fs::path temp = (target.has_parent_path() ? target.parent_path() : fs::path(".")) /
                          ("." + target.filename().string() + ".part-" + random_hex(4));
    HttpRequest req;
    req.target = "/v1/jobs/" + job_id + "/files/" + url_escape(name);
    req.reply_file = temp.string();
    Result<HttpReply> r = impl_->call(std::move(req));
    if (!r.ok() || r->status != 200) {
      std::error_code ec;
      fs::remove(temp, ec);
      if (!r.ok()) return r.error();
      return http_error(r.value(), "fetch " + name);
    }
    if (auto e = fsync_and_rename(temp, target)) {
      std::error_code ec;
      fs::remove(temp, ec);
      return *e;
    }
    return target.string();
  });
}

Result<FetchedFiles> Client::fetch_results(const std::string& job_id, const std::string& out_dir) {
  return guarded<FetchedFiles>([&]() -> Result<FetchedFiles> {
    Result<proto::JobResult> r = result(job_id);
    if (!r.ok()) return r.error();
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (ec) return make_error(ErrorCode::kIo, "cannot create " + out_dir + ": " + ec.message());
    FetchedFiles fetched;
    for (const auto& f : r->files) {
      if (!safe_file_name(f.name))
        return make_error(ErrorCode::kProtocol, "the server listed a bad file name \"" + f.name + "\"");
      const fs::path target = fs::path(out_dir) / f.name;
      Result<std::string> p = fetch_file_to(job_id, f.name, target.string());
      if (!p.ok()) return p.error();
      const auto size = fs::file_size(target, ec);
      if (ec || size != f.bytes) {
        return make_error(ErrorCode::kProtocol, f.name + ": received " + std::to_string(ec ? 0 : size) +
                                                    " bytes, the result lists " + std::to_string(f.bytes));
      }
      fetched.paths.push_back(p.value());
    }
    fetched.result = std::move(r.value());
    return fetched;
  });
}

Result<FetchedFiles> Client::run(const proto::JobSpec& job, const std::string& out_dir,
                                 const WaitOptions& wait_options) {
  return guarded<FetchedFiles>([&]() -> Result<FetchedFiles> {
    Result<proto::JobStatus> submitted = submit(job);
    if (!submitted.ok()) return submitted.error();
    Result<proto::JobStatus> done = wait(submitted->id, wait_options);
    if (!done.ok()) return done.error();
    if (done->state == proto::JobState::kFailed) {
      ClientError e = make_error(ErrorCode::kJobFailed, "job " + done->id + " failed" +
                                                            (done->error ? ": " + done->error->detail : std::string()));
      e.problem = done->error;
      return e;
    }
    if (done->state == proto::JobState::kCanceled) {
      return make_error(ErrorCode::kJobCanceled, "job " + done->id + " was canceled");
    }
    return fetch_results(done->id, out_dir);
  });
}

Result<std::string> Client::ready() {
  return guarded<std::string>([&]() -> Result<std::string> {
    HttpRequest req;
    req.target = "/readyz";
    Result<HttpReply> r = impl_->call(std::move(req), false);
    if (!r.ok()) return r.error();
    if (r->status != 200 && r->status != 503) return http_error(r.value(), "readyz");
    return decode_reply<std::string>(r.value(), "readyz", [](const nlohmann::json& j) {
      if (!j.is_object()) throw std::runtime_error("expected a JSON object");
      return proto::safe_dump(j);
    });
  });
}

}  // namespace texwarp::client
