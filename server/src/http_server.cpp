// Connections and requests over Beast: see http_server.hpp.
#include "texwarp/server/http_server.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>

#include <boost/asio/dispatch.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "texwarp/server/json_log.hpp"

namespace texwarp::server {

namespace asio = boost::asio;
namespace beast = boost::beast;
using tcp = asio::ip::tcp;

struct HttpServer::Shared {
  const ServerConfig& config;
  ApiRouter& router;
  Metrics& metrics;
  JobService& service;
};

namespace {

using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kDiscardableBody = 1 << 20;   // a refused request's body up to this is read and dropped
constexpr std::size_t kLingerBytes = 64 << 20;         // after a refusal that closes: bytes read and dropped at most
constexpr auto kLingerTime = std::chrono::seconds(2);

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
  try {
    return std::stoull(std::string(length));
  } catch (...) {
    return UINT64_MAX;
  }
}

class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket&& socket, std::shared_ptr<HttpServer::Shared> shared,
          std::shared_ptr<std::atomic<std::size_t>> connections, bool over_capacity)
      : stream_(std::move(socket)),
        body_timer_(stream_.get_executor()),
        shared_(std::move(shared)),
        connections_(std::move(connections)),
        over_capacity_(over_capacity) {
    connections_->fetch_add(1);
  }
  ~Session() {
    discard_upload();
    connections_->fetch_sub(1);
  }

  void run() {
    asio::dispatch(stream_.get_executor(), [self = shared_from_this()] {
      if (self->over_capacity_) {
        self->fail_early(ApiError(503, "too-many-connections", "Too many connections",
                                  "the server has too many open connections; retry shortly")
                             .retry_after(1));
        return;
      }
      self->read_header();
    });
  }

 private:
  const ServerConfig& config() const { return shared_->config; }

  void read_header() {
    header_parser_.emplace();
    header_parser_->header_limit(config().max_header_bytes);
    // The route's limit applies once the body is read (plan()). Not boost::none: Boost 1.74 compares it as 0.
    header_parser_->body_limit(std::numeric_limits<std::uint64_t>::max());
    stream_.expires_after(seconds(first_ ? config().read_timeout_s : config().idle_timeout_s));
    http::async_read_header(stream_, buffer_, *header_parser_,
                            beast::bind_front_handler(&Session::on_header, shared_from_this()));
  }

  void on_header(beast::error_code ec, std::size_t) {
    if (ec) {
      if (ec == http::error::header_limit) {
        return fail_early(ApiError(431, "header-too-large", "Request header fields too large",
                                   "the request header is larger than " + std::to_string(config().max_header_bytes) +
                                       " bytes"));
      }
      const beast::error_code http_error = http::error::end_of_stream;
      if (ec.category() == http_error.category() && ec != http::error::end_of_stream &&
          ec != http::error::partial_message) {
        return fail_early(ApiError(400, "malformed-request", "Malformed HTTP request", "cannot parse the request: " + ec.message()));
      }
      return close();  // end of stream, timeout while idle, reset
    }
    first_ = false;
    started_ = Clock::now();
    const auto& message = header_parser_->get();
    const RequestHeader& req = message;
    request_id_ = request_id_of(req);
    method_ = std::string(req.method_string());
    target_ = std::string(req.target());
    plan_ = shared_->router.plan(req);
    const bool expects_continue = beast::iequals(req[http::field::expect], "100-continue");
    if (plan_.refusal) {
      if (!has_body(req)) return respond(shared_->router.handle(req, {}, plan_, request_id_), !message.keep_alive());
      if (expects_continue) {  // the client waits for a 100 before sending its body: answer now, then close
        linger_ = true;
        return respond(shared_->router.handle(req, {}, plan_, request_id_), true);
      }
      if (plan_.refusal->status() != 413 && declared_length(req) <= kDiscardableBody) {
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

  // The body has --read-timeout to arrive. A timer of its own (not the stream's, which would close the socket)
  // cancels the read, so that a 408 can still be sent.
  void read_body() {
    stream_.expires_never();
    body_timer_.expires_after(seconds(config().read_timeout_s));
    body_timer_.async_wait([weak = weak_from_this()](beast::error_code ec) {
      auto self = weak.lock();
      if (ec || !self) return;
      self->body_timed_out_ = true;
      beast::error_code ignored;
      self->stream_.socket().cancel(ignored);
    });
    if (plan_.body == RequestPlan::Body::kFile) {
      file_parser_.emplace(std::move(*header_parser_));
      file_parser_->body_limit(plan_.body_limit);
      beast::error_code ec;
      file_parser_->get().body().open(plan_.upload_file.c_str(), beast::file_mode::write, ec);
      if (ec) {
        log_event(LogLevel::kError, "cannot open an upload file", {{"request_id", request_id_}, {"error", ec.message()}});
        return fail_early(ApiError(500, "internal", "Internal server error",
                                   "the server could not store the upload; quote request id " + request_id_));
      }
      if (file_parser_->is_done()) return on_body({}, 0);
      http::async_read(stream_, buffer_, *file_parser_, beast::bind_front_handler(&Session::on_body, shared_from_this()));
    } else {
      string_parser_.emplace(std::move(*header_parser_));
      string_parser_->body_limit(plan_.body_limit);
      if (string_parser_->is_done()) return on_body({}, 0);
      http::async_read(stream_, buffer_, *string_parser_,
                       beast::bind_front_handler(&Session::on_body, shared_from_this()));
    }
  }

  void on_body(beast::error_code ec, std::size_t) {
    body_timer_.cancel();
    if (body_timed_out_) {
      return fail_early(ApiError(408, "request-timeout", "Request timeout",
                                 "the request body did not arrive within " + format_seconds(config().read_timeout_s) + " s"));
    }
    if (ec == http::error::body_limit) {
      linger_ = true;
      return fail_early(ApiError(413, "body-too-large", "Request body too large",
                                 "the body is larger than " + std::to_string(plan_.body_limit) + " bytes, the most this route accepts"));
    }
    if (ec) return close();
    bool keep_alive = true;
    ApiResponse response;
    if (plan_.body == RequestPlan::Body::kFile) {
      auto& req = file_parser_->get();
      keep_alive = req.keep_alive();
      req.body().close();
      response = shared_->router.handle(req, {}, plan_, request_id_);
    } else {
      auto& req = string_parser_->get();
      keep_alive = req.keep_alive();
      response = shared_->router.handle(req, discard_body_ ? std::string() : req.body(), plan_, request_id_);
    }
    respond(std::move(response), !keep_alive || shared_->service.draining());
  }

  // A response to a request whose header could not be read or whose body is refused mid-way: closes afterwards.
  void fail_early(const ApiError& error) {
    if (started_ == Clock::time_point{}) started_ = Clock::now();
    if (request_id_.empty()) request_id_ = new_request_id();
    respond(shared_->router.problem(error, target_.substr(0, target_.find('?')), 11, request_id_), true);
  }

  // Counts and logs the request (before sending, so that a client that has the answer also finds it counted), then
  // sends the answer.
  void respond(ApiResponse response, bool close_after) {
    status_ = response_status(response);
    const double elapsed = std::chrono::duration<double>(Clock::now() - started_).count();
    shared_->metrics.observe_request(plan_.route, method_, static_cast<int>(status_), elapsed);
    const bool probe = plan_.route == "/livez" || plan_.route == "/readyz" || plan_.route == "/metrics";
    log_event(status_ >= 500 ? LogLevel::kError : probe ? LogLevel::kDebug : LogLevel::kInfo, "request",
              {{"request_id", request_id_},
               {"method", method_},
               {"target", target_.substr(0, 200)},
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
          http::async_write(stream_, *held, [self = shared_from_this(), held, close_after](beast::error_code ec, std::size_t) {
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
    read_header();
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
    linger();
  }

  void linger() {
    stream_.expires_at(linger_deadline_);
    stream_.async_read_some(asio::buffer(drain_), [self = shared_from_this()](beast::error_code ec, std::size_t n) {
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
  asio::steady_timer body_timer_;
  bool body_timed_out_ = false;
  beast::flat_buffer buffer_;
  std::shared_ptr<HttpServer::Shared> shared_;
  std::shared_ptr<std::atomic<std::size_t>> connections_;
  bool over_capacity_ = false;
  bool first_ = true;
  bool discard_body_ = false;
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
  std::array<char, 64 << 10> drain_{};
};

}  // namespace

HttpServer::HttpServer(asio::io_context& ioc, const ServerConfig& config, ApiRouter& router, Metrics& metrics,
                       JobService& service)
    : ioc_(ioc),
      acceptor_(asio::make_strand(ioc)),
      shared_(std::make_shared<Shared>(Shared{config, router, metrics, service})),
      connections_(std::make_shared<std::atomic<std::size_t>>(0)) {}

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
  });
}

void HttpServer::accept() {
  acceptor_.async_accept(asio::make_strand(ioc_), [this](beast::error_code ec, tcp::socket socket) {
    if (ec == asio::error::operation_aborted || !acceptor_.is_open()) return;
    if (!ec) {
      beast::error_code nodelay_ec;
      socket.set_option(tcp::no_delay(true), nodelay_ec);
      const bool over = connections_->load() >= shared_->config.max_connections;
      std::make_shared<Session>(std::move(socket), shared_, connections_, over)->run();
    }
    accept();
  });
}

}  // namespace texwarp::server
