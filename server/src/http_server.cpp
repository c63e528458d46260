// Connections and requests over Beast: see http_server.hpp.
#include "texwarp/server/http_server.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <string>
#include <unordered_map>

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/server/declared_length.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/storage_full.hpp"

namespace texwarp::server {

namespace asio = boost::asio;
namespace beast = boost::beast;
using tcp = asio::ip::tcp;

struct HttpServer::Shared {
  Shared(const ServerConfig& c, ApiRouter& r, Metrics& m, JobService& s, asio::thread_pool& p)
      : config(c), router(r), metrics(m), service(s), pool(p) {}

  const ServerConfig& config;
  ApiRouter& router;
  Metrics& metrics;
  JobService& service;
  asio::thread_pool& pool;

  std::mutex mutex;                                         // guards what follows
  std::unordered_map<std::string, std::size_t> per_client;  // open connections by client address
  // Keep-alive connections waiting for their next request (no byte of it read yet), oldest first: closing one
  // frees its slot for a newcomer when the server is at max_connections.
  std::map<std::uint64_t, std::function<void()>> idle;
  std::uint64_t next_idle = 0;
  std::size_t probe_sessions = 0;  // connections over capacity that may only ask /livez and /readyz
};

namespace {

using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kDiscardableBody = 1 << 20;  // a refused request's body up to this is read and dropped
constexpr std::size_t kLingerBytes = 64 << 20;       // after a refusal that closes: bytes read and dropped at most
constexpr auto kLingerTime = std::chrono::seconds(2);
constexpr double kProbeHeaderTimeoutS = 2.0;   // over capacity: a connection's header must come this fast
constexpr std::size_t kMaxProbeSessions = 64;  // over capacity: connections kept to answer probes, at most
constexpr std::string_view kFullAnswer =       // beyond them: this, then the connection is closed
    "HTTP/1.1 503 Service Unavailable\r\nRetry-After: 1\r\nConnection: close\r\nContent-Length: 0\r\n\r\n";
constexpr auto kMinAcceptBackoff = std::chrono::milliseconds(10);
constexpr auto kMaxAcceptBackoff = std::chrono::milliseconds(1000);

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

std::string format_seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", s);
  return buf;
}

std::string new_request_id() {
  thread_local std::mt19937_64 rng(std::random_device{}());
  static constexpr char kHex[] = "0123456789abcdef";
  std::string id;
  std::uint64_t v = rng();
  for (int i = 0; i < 16; ++i, v >>= 4) id.push_back(kHex[v & 15]);
  return id;
}

std::string request_id_of(const RequestHeader& h) {
  const auto given = h["X-Request-Id"];
  const bool ok = !given.empty() && given.size() <= 64 && std::all_of(given.begin(), given.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.';
  });
  return ok ? std::string(given) : new_request_id();
}

bool has_body(const RequestHeader& h) {
  const auto length = h[http::field::content_length];
  return (!length.empty() && length != "0") || !h[http::field::transfer_encoding].empty();
}

std::uint64_t declared_length(const RequestHeader& h) {
  const auto length = h[http::field::content_length];
  if (length.empty()) return h[http::field::transfer_encoding].empty() ? 0 : UINT64_MAX;
  return declared_content_length(length).value_or(UINT64_MAX);
}

class Session : public std::enable_shared_from_this<Session> {
 public:
  // `over_capacity`: why this connection may only ask /livez or /readyz ("" : a connection like any other).
  Session(tcp::socket&& socket, std::shared_ptr<HttpServer::Shared> shared,
          std::shared_ptr<std::atomic<std::size_t>> connections, std::string client, std::string over_capacity)
      : stream_(std::move(socket)),
        body_timer_(stream_.get_executor()),
        wait_timer_(stream_.get_executor()),
        shared_(std::move(shared)),
        connections_(std::move(connections)),
        client_(std::move(client)),
        over_capacity_(std::move(over_capacity)) {
    connections_->fetch_add(1);
  }
  ~Session() {
    discard_upload();
    {
      std::lock_guard lock(shared_->mutex);
      if (idle_serial_) shared_->idle.erase(*idle_serial_);
      if (!over_capacity_.empty()) --shared_->probe_sessions;
      if (auto it = shared_->per_client.find(client_); it != shared_->per_client.end() && --it->second == 0) {
        shared_->per_client.erase(it);
      }
    }
    connections_->fetch_sub(1);
  }

  void run() {
    asio::dispatch(stream_.get_executor(), [self = shared_from_this()] {
      self->read_header(self->over_capacity_.empty() ? self->config().read_timeout_s
                                                     : std::min(kProbeHeaderTimeoutS, self->config().read_timeout_s));
    });
  }

 private:
  const ServerConfig& config() const { return shared_->config; }

  void read_header(double timeout_s) {
    header_parser_.emplace();
    header_parser_->header_limit(config().max_header_bytes);
    // The route's limit applies once the body is read (plan()). Not boost::none: Boost 1.74 compares it as 0.
    header_parser_->body_limit(std::numeric_limits<std::uint64_t>::max());
    stream_.expires_after(seconds(timeout_s));
    http::async_read_header(stream_, buffer_, *header_parser_,
                            beast::bind_front_handler(&Session::on_header, shared_from_this()));
  }

  // Between requests of a keep-alive connection: waits (up to --idle-timeout) for the first byte of the next one.
  // Until it comes the connection is idle, and a newcomer may have it closed when the server is at capacity.
  void wait_for_request() {
    if (buffer_.size() > 0) return read_header(config().read_timeout_s);  // pipelined: the next request is here
    stream_.expires_never();
    {
      std::lock_guard lock(shared_->mutex);
      idle_serial_ = ++shared_->next_idle;
      shared_->idle.emplace(*idle_serial_, [weak = weak_from_this()] {
        if (auto self = weak.lock()) {
          asio::post(self->stream_.get_executor(), [self] {
            beast::error_code ignored;
            self->stream_.socket().cancel(ignored);
          });
        }
      });
    }
    arm_timer(config().idle_timeout_s, [](Session& self) {
      beast::error_code ignored;
      self.stream_.socket().cancel(ignored);
    });
    stream_.socket().async_wait(tcp::socket::wait_read,
                                beast::bind_front_handler(&Session::on_readable, shared_from_this()));
  }

  void on_readable(beast::error_code ec) {
    disarm_timer();
    bool evicted = false;
    {
      std::lock_guard lock(shared_->mutex);
      evicted = shared_->idle.erase(*idle_serial_) == 0;  // a newcomer took this connection's slot
      idle_serial_.reset();
    }
    if (ec || evicted) return close();
    read_header(config().read_timeout_s);
  }

  // body_timer_ calls `on_expiry` after `timeout_s` unless disarmed (or re-armed) first.
  void arm_timer(double timeout_s, void (*on_expiry)(Session&)) {
    const std::uint64_t generation = ++timer_generation_;
    body_timer_.expires_after(seconds(timeout_s));
    body_timer_.async_wait([weak = weak_from_this(), generation, on_expiry](beast::error_code ec) {
      auto self = weak.lock();
      if (ec || !self || self->timer_generation_ != generation) return;
      on_expiry(*self);
    });
  }

  void disarm_timer() {
    ++timer_generation_;
    body_timer_.cancel();
  }

  void on_header(beast::error_code ec, std::size_t) {
    if (ec) {
      if (ec == http::error::header_limit) {
        return fail_early(
            ServiceError(ErrorKind::kHeaderTooLarge,
                         "the request header is larger than " + std::to_string(config().max_header_bytes) + " bytes"));
      }
      if (is_malformed(ec)) {
        return fail_early(ServiceError(ErrorKind::kMalformedRequest, "cannot parse the request: " + ec.message()));
      }
      return close();  // end of stream, timeout while idle, reset
    }
    started_ = Clock::now();
    const auto& message = header_parser_->get();
    const RequestHeader& req = message;
    request_id_ = request_id_of(req);
    method_ = std::string(req.method_string());
    target_ = std::string(req.target());
    if (!over_capacity_.empty() && !ApiRouter::is_open_path(req.target())) {
      linger_ = has_body(req);
      return fail_early(ServiceError(ErrorKind::kTooManyConnections,
                                     over_capacity_ + "; retry shortly (GET /livez and /readyz are always answered)"));
    }
    try {
      plan_ = shared_->router.plan(req);
    } catch (const std::exception& e) {
      log_event(LogLevel::kError, "internal error", {{"request_id", request_id_}, {"error", e.what()}});
      plan_ = RequestPlan{};
      plan_.refusal = ServiceError(ErrorKind::kInternal,
                                   "the server could not answer this request; quote request id " + request_id_);
    }
    const bool expects_continue = beast::iequals(req[http::field::expect], "100-continue");
    if (plan_.refusal) {
      if (!has_body(req)) return respond(shared_->router.handle(req, {}, plan_, request_id_), !message.keep_alive());
      if (expects_continue) {  // the client waits for a 100 before sending its body: answer now, then close
        linger_ = true;
        return respond(shared_->router.handle(req, {}, plan_, request_id_), true);
      }
      if (plan_.refusal->kind() != ErrorKind::kBodyTooLarge && declared_length(req) <= kDiscardableBody) {
        discard_body_ = true;
        plan_.body = RequestPlan::Body::kMemory;
        plan_.body_limit = kDiscardableBody;
        return read_body();
      }
      linger_ = true;
      return respond(shared_->router.handle(req, {}, plan_, request_id_), true);
    }
    if (expects_continue) {
      auto cont = std::make_shared<EmptyResponse>(http::status::continue_, req.version());
      stream_.expires_after(seconds(config().write_timeout_s));
      http::async_write(stream_, *cont, [self = shared_from_this(), cont](beast::error_code wec, std::size_t) {
        if (wec) return self->close();
        self->read_body();
      });
      return;
    }
    read_body();
  }

  // A parse error of Beast's (bad framing, bad chunk, bad field), as opposed to the peer going away.
  static bool is_malformed(const beast::error_code& ec) {
    const beast::error_code http_error = http::error::end_of_stream;
    return ec.category() == http_error.category() && ec != http::error::end_of_stream &&
           ec != http::error::partial_message;
  }

  // The body has --read-timeout to arrive. A timer of its own (not the stream's, which would close the socket)
  // cancels the read, so that a 408 can still be sent.
  void read_body() {
    stream_.expires_never();
    arm_timer(config().read_timeout_s, [](Session& self) {
      self.body_timed_out_ = true;
      beast::error_code ignored;
      self.stream_.socket().cancel(ignored);
    });
    if (plan_.body == RequestPlan::Body::kFile) {
      file_parser_.emplace(std::move(*header_parser_));
      file_parser_->body_limit(plan_.body_limit);
      beast::error_code ec;
      file_parser_->get().body().open(plan_.upload_file.c_str(), beast::file_mode::write, ec);
      if (ec) {
        disarm_timer();
        log_event(LogLevel::kError, "cannot open an upload file",
                  {{"request_id", request_id_}, {"error", ec.message()}});
        linger_ = true;
        if (is_storage_full(ec)) return fail_early(storage_full_error("the upload was not stored"));
        return fail_early(ServiceError(ErrorKind::kInternal,
                                       "the server could not store the upload; quote request id " + request_id_));
      }
      if (file_parser_->is_done()) return on_body({}, 0);
      http::async_read(stream_, buffer_, *file_parser_,
                       beast::bind_front_handler(&Session::on_body, shared_from_this()));
    } else {
      string_parser_.emplace(std::move(*header_parser_));
      string_parser_->body_limit(plan_.body_limit);
      if (string_parser_->is_done()) return on_body({}, 0);
      http::async_read(stream_, buffer_, *string_parser_,
                       beast::bind_front_handler(&Session::on_body, shared_from_this()));
    }
  }

  void on_body(beast::error_code ec, std::size_t) {
    disarm_timer();
    if (body_timed_out_) {
      return fail_early(ServiceError(ErrorKind::kRequestTimeout, "the request body did not arrive within " +
                                                                     format_seconds(config().read_timeout_s) + " s"));
    }
    if (ec == http::error::body_limit) {
      linger_ = true;
      return fail_early(ServiceError(ErrorKind::kBodyTooLarge, "the body is larger than " +
                                                                   std::to_string(plan_.body_limit) +
                                                                   " bytes, the most this route accepts"));
    }
    if (ec && is_storage_full(ec)) {
      log_event(LogLevel::kError, "storage full: an upload was refused",
                {{"request_id", request_id_}, {"error", ec.message()}});
      linger_ = true;
      return fail_early(storage_full_error("the upload was not stored"));
    }
    if (ec && is_malformed(ec)) {
      linger_ = true;
      return fail_early(ServiceError(ErrorKind::kMalformedRequest, "cannot read the request body: " + ec.message()));
    }
    if (ec) return close();
    keep_alive_ =
        plan_.body == RequestPlan::Body::kFile ? file_parser_->get().keep_alive() : string_parser_->get().keep_alive();
    if (plan_.off_io_thread && !plan_.refusal) {
      // Parsing, decoding and storing a body can take long: never on an I/O thread, where it would stall every
      // connection that shares it. The answer is sent from this connection's strand.
      asio::post(shared_->pool, [self = shared_from_this()] {
        auto response = std::make_shared<ApiResponse>(self->handle_request());
        asio::post(self->stream_.get_executor(), [self, response] { self->answer(std::move(*response)); });
      });
      return;
    }
    answer(handle_request());
  }

  // Sends the router's answer, or, when the handler deferred it, waits for it without holding a thread.
  void answer(ApiResponse response) {
    if (!plan_.deferred) return respond(std::move(response), !keep_alive_ || shared_->service.draining());
    if (plan_.deferred->subscribe) {
      wake_token_ = plan_.deferred->subscribe([weak = weak_from_this()] {
        if (auto self = weak.lock()) asio::post(self->stream_.get_executor(), [self] { self->poll_deferred(false); });
      });
    }
    schedule_deferred();
  }

  void schedule_deferred() {
    const DeferredAnswer& d = *plan_.deferred;
    wait_timer_.expires_at(std::min(Clock::now() + d.interval, d.deadline));
    wait_timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec || !self->plan_.deferred) return;
      self->poll_deferred(true);
    });
  }

  // Asks the deferred answer again (`timer`: at its recheck interval, else woken); sends it once there is one. A
  // draining server answers at once (the state as it is), so that waiting clients are not cut off at the end.
  void poll_deferred(bool timer) {
    if (!plan_.deferred) return;  // answered already
    const bool final = (timer && Clock::now() >= plan_.deferred->deadline) || shared_->service.draining();
    std::optional<ApiResponse> response = plan_.deferred->poll(final);
    if (!response) {
      if (timer) schedule_deferred();
      return;
    }
    wake_token_.reset();
    plan_.deferred.reset();
    wait_timer_.cancel();
    respond(std::move(*response), !keep_alive_ || shared_->service.draining());
  }

  // The router's answer to the whole request (never throws).
  ApiResponse handle_request() {
    try {
      if (plan_.body == RequestPlan::Body::kFile) {
        auto& req = file_parser_->get();
        req.body().close();
        return shared_->router.handle(req, {}, plan_, request_id_);
      }
      auto& req = string_parser_->get();
      return shared_->router.handle(req, discard_body_ ? std::string() : req.body(), plan_, request_id_);
    } catch (const std::exception& e) {
      log_event(LogLevel::kError, "internal error", {{"request_id", request_id_}, {"error", e.what()}});
      return shared_->router.problem(
          ServiceError(ErrorKind::kInternal,
                       "the server could not answer this request; quote request id " + request_id_),
          target_.substr(0, target_.find('?')), 11, request_id_);
    }
  }

  // A response to a request whose header could not be read or whose body is refused mid-way: closes afterwards.
  void fail_early(const ServiceError& error) {
    discard_upload();  // gone before the client can see the answer
    if (started_ == Clock::time_point{}) started_ = Clock::now();
    if (request_id_.empty()) request_id_ = new_request_id();
    respond(shared_->router.problem(error, target_.substr(0, target_.find('?')), 11, request_id_), true);
  }

  // Counts and logs the request (before sending, so that a client that has the answer also finds it counted), then
  // sends the answer. A connection over capacity is closed after its answer.
  void respond(ApiResponse response, bool close_after) {
    close_after = close_after || !over_capacity_.empty();
    status_ = response_status(response);
    const double elapsed = std::chrono::duration<double>(Clock::now() - started_).count();
    shared_->metrics.observe_request(plan_.route, method_, static_cast<int>(status_), elapsed);
    log_event(status_ >= 500 ? LogLevel::kError
              : plan_.quiet  ? LogLevel::kDebug
                             : LogLevel::kInfo,
              "request",
              {{"request_id", request_id_},
               {"method", method_},
               {"target", proto::utf8_prefix(target_, 200)},
               {"client", client_},
               {"route", plan_.route},
               {"status", status_},
               {"ms", std::round(elapsed * 1e6) / 1e3}});
    plan_.idempotency_claim.reset();  // answered: a retry with the key now gets this answer replayed, not 409
    std::visit(
        [&](auto& r) {
          using Response = std::decay_t<decltype(r)>;
          r.keep_alive(!close_after);
          r.set(http::field::server, "texwarpd");
          auto held = std::make_shared<Response>(std::move(r));
          stream_.expires_after(seconds(config().write_timeout_s));
          http::async_write(stream_, *held,
                            [self = shared_from_this(), held, close_after](beast::error_code ec, std::size_t) {
                              self->on_write(ec, close_after);
                            });
        },
        response);
  }

  void on_write(beast::error_code ec, bool close_after) {
    discard_upload();
    plan_ = RequestPlan{};
    header_parser_.reset();
    string_parser_.reset();
    file_parser_.reset();
    discard_body_ = false;
    method_.clear();
    target_.clear();
    request_id_.clear();
    started_ = {};
    if (ec || close_after) return close();
    wait_for_request();
  }

  void discard_upload() {
    if (!plan_.upload_file.empty()) {
      std::error_code ec;
      std::filesystem::remove(plan_.upload_file, ec);  // adopted uploads were renamed away already
      plan_.upload_file.clear();
    }
  }

  void close() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    if (!linger_ || ec) {
      stream_.socket().close(ec);
      return;
    }
    // Read and drop what the client still sends, so that closing does not reset the connection before it has
    // read the response.
    linger_deadline_ = Clock::now() + kLingerTime;
    drain_ = std::make_unique<std::array<char, 64 << 10>>();
    linger();
  }

  void linger() {
    stream_.expires_at(linger_deadline_);
    stream_.async_read_some(asio::buffer(*drain_), [self = shared_from_this()](beast::error_code ec, std::size_t n) {
      self->lingered_ += n;
      if (ec || self->lingered_ > kLingerBytes) {
        beast::error_code ignored;
        self->stream_.socket().close(ignored);
        return;
      }
      self->linger();
    });
  }

  beast::tcp_stream stream_;
  asio::steady_timer body_timer_;     // the body's read timeout, or the idle timeout between requests
  asio::steady_timer wait_timer_;     // a deferred answer's next recheck
  std::shared_ptr<void> wake_token_;  // a deferred answer's wake-ups
  std::uint64_t timer_generation_ = 0;
  bool body_timed_out_ = false;
  beast::flat_buffer buffer_;
  std::shared_ptr<HttpServer::Shared> shared_;
  std::shared_ptr<std::atomic<std::size_t>> connections_;
  std::string client_;         // the peer's IP address
  std::string over_capacity_;  // why only probes are answered on this connection; empty: not over capacity
  std::optional<std::uint64_t> idle_serial_;  // the key in shared_->idle while waiting for a request
  bool discard_body_ = false;
  bool keep_alive_ = true;
  bool linger_ = false;
  std::optional<http::request_parser<http::empty_body>> header_parser_;
  std::optional<http::request_parser<http::string_body>> string_parser_;
  std::optional<http::request_parser<http::file_body>> file_parser_;
  RequestPlan plan_;
  std::string request_id_;
  std::string method_;
  std::string target_;
  unsigned status_ = 0;
  Clock::time_point started_{};
  Clock::time_point linger_deadline_{};
  std::size_t lingered_ = 0;
  std::unique_ptr<std::array<char, 64 << 10>> drain_;  // while lingering only
};

}  // namespace

HttpServer::HttpServer(asio::io_context& ioc, const ServerConfig& config, ApiRouter& router, Metrics& metrics,
                       JobService& service)
    : ioc_(ioc),
      pool_(static_cast<std::size_t>(std::max(config.io_threads, 1))),
      acceptor_(asio::make_strand(ioc)),
      accept_timer_(acceptor_.get_executor()),
      shared_(std::make_shared<Shared>(config, router, metrics, service, pool_)),
      connections_(std::make_shared<std::atomic<std::size_t>>(0)) {}

HttpServer::~HttpServer() { pool_.join(); }

unsigned short HttpServer::start() {
  const ServerConfig& c = shared_->config;
  beast::error_code ec;
  const auto address = asio::ip::make_address(c.host, ec);
  if (ec) throw std::runtime_error("--listen: \"" + c.host + "\" is not an IP address (use e.g. 127.0.0.1 or ::1)");
  const tcp::endpoint endpoint(address, c.port);
  acceptor_.open(endpoint.protocol());
  acceptor_.set_option(asio::socket_base::reuse_address(true));
  acceptor_.bind(endpoint, ec);
  if (ec) throw std::runtime_error("cannot listen on " + c.host + ":" + std::to_string(c.port) + ": " + ec.message());
  acceptor_.listen(asio::socket_base::max_listen_connections);
  const unsigned short port = acceptor_.local_endpoint().port();
  accept();
  return port;
}

void HttpServer::stop_accepting() {
  asio::dispatch(acceptor_.get_executor(), [this] {
    beast::error_code ec;
    acceptor_.close(ec);
    accept_timer_.cancel();
  });
}

void HttpServer::accept() {
  acceptor_.async_accept(asio::make_strand(ioc_), [this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor_.is_open()) return;
    if (ec) return on_accept_error(ec);
    if (accept_failing_) {
      accept_failing_ = false;
      log_event(LogLevel::kInfo, "accepting connections again");
    }
    accept_backoff_ = std::chrono::milliseconds(0);
    on_accept(std::move(socket));
    accept();
  });
}

void HttpServer::on_accept_error(const boost::system::error_code& ec) {
  if (ec == asio::error::connection_aborted) return accept();  // that client gave up; the next one may be waiting
  accept_backoff_ = std::clamp(accept_backoff_ * 2, std::chrono::milliseconds(kMinAcceptBackoff), kMaxAcceptBackoff);
  if (!accept_failing_) {
    accept_failing_ = true;
    const bool out_of_descriptors =
        ec == boost::system::errc::too_many_files_open || ec == boost::system::errc::too_many_files_open_in_system;
    log_event(LogLevel::kError,
              out_of_descriptors ? "cannot accept connections: out of file descriptors" : "cannot accept connections",
              {{"error", ec.message()},
               {"open_connections", connections_->load()},
               {"hint", out_of_descriptors ? "raise the descriptor limit (ulimit -n) or lower --max-connections"
                                           : "retrying with a growing delay"}});
  }
  accept_timer_.expires_after(accept_backoff_);
  accept_timer_.async_wait([this](beast::error_code wec) {
    if (wec || !acceptor_.is_open()) return;
    accept();
  });
}

void HttpServer::on_accept(tcp::socket socket) {
  beast::error_code ec;
  socket.set_option(tcp::no_delay(true), ec);
  const auto remote = socket.remote_endpoint(ec);
  std::string client = ec ? std::string() : remote.address().to_string();
  const ServerConfig& c = shared_->config;
  std::string over_capacity;
  std::function<void()> evict;
  {
    std::lock_guard lock(shared_->mutex);
    std::size_t& open = shared_->per_client[client];
    if (open >= c.max_connections_per_client) {
      over_capacity = "this client has " + std::to_string(open) + " connections open, the most one client may have";
    } else if (connections_->load() >= c.max_connections) {
      if (shared_->idle.empty()) {
        over_capacity = "the server has " + std::to_string(c.max_connections) + " connections open, its maximum";
      } else {
        evict = std::move(shared_->idle.begin()->second);  // the connection idle the longest makes room
        shared_->idle.erase(shared_->idle.begin());
      }
    }
    if (!over_capacity.empty() && shared_->probe_sessions >= kMaxProbeSessions) {
      // Enough connections already wait to ask a probe: a flood of silent ones must not run the process out of
      // descriptors (then not even probes could be answered). A short 503 and close, on the spot.
      socket.non_blocking(true, ec);
      asio::write(socket, asio::buffer(kFullAnswer.data(), kFullAnswer.size()), ec);
      socket.close(ec);
      return;
    }
    if (!over_capacity.empty()) ++shared_->probe_sessions;
    ++open;
  }
  if (evict) evict();
  std::make_shared<Session>(std::move(socket), shared_, connections_, std::move(client), std::move(over_capacity))
      ->run();
}

}  // namespace texwarp::server
