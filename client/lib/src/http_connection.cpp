// One keep-alive HTTP/1.1 connection with deadlines: see http_connection.hpp.
#include "http_connection.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stop_token>

#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

namespace texwarp::client {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;

namespace {

constexpr std::uint64_t kMaxReplyBytes = 1ULL << 30;  // in memory; files streamed to disk have no limit

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

ClientError error(ErrorCode code, std::string message) {
  return ClientError{code, 0, std::move(message), std::nullopt, std::nullopt};
}

}  // namespace

struct HttpConnection::Impl {
  std::string host;
  std::string port;
  std::chrono::milliseconds connect_timeout;
  std::chrono::milliseconds request_timeout;
  std::string user_agent;
  asio::io_context ioc;
  std::optional<beast::tcp_stream> stream;
  beast::flat_buffer buffer;
  bool reused = false;   // the connection has carried an exchange before
  std::stop_token stop;  // the current exchange's

  // Runs one async operation started by `start` to completion on the private io_context; a stop requested
  // meanwhile (from any thread) cancels it there, so it ends at once with operation_aborted.
  template <typename Start>
  beast::error_code run(Start&& start) {
    beast::error_code result;
    ioc.restart();
    start([&result](beast::error_code ec, auto&&...) { result = ec; });
    if (!stop.stop_possible()) {
      ioc.run();
      return result;
    }
    std::stop_callback on_stop(stop, [this] {
      asio::post(ioc, [this] {
        if (stream) stream->cancel();
      });
    });
    ioc.run();
    return result;
  }

  void close() {
    if (stream) {
      beast::error_code ec;
      stream->socket().shutdown(tcp::socket::shutdown_both, ec);
      stream->socket().close(ec);
      stream.reset();
    }
    buffer.clear();
    reused = false;
  }

  std::optional<ClientError> connect() {
    close();
    tcp::resolver resolver(ioc);
    beast::error_code ec;
    const auto endpoints = resolver.resolve(host, port, ec);
    if (ec) return error(ErrorCode::kConnection, "cannot resolve " + host + ": " + ec.message());
    stream.emplace(ioc);
    stream->expires_after(connect_timeout);
    ec = run([&](auto handler) {
      stream->async_connect(endpoints, [handler](beast::error_code e, const tcp::endpoint&) mutable { handler(e); });
    });
    if (ec) {
      const bool timeout = ec == beast::error::timeout;
      close();
      return error(timeout ? ErrorCode::kTimeout : ErrorCode::kConnection,
                   "cannot connect to " + host + ":" + port + ": " + (timeout ? "timed out" : ec.message()));
    }
    beast::error_code nodelay;
    stream->socket().set_option(tcp::no_delay(true), nodelay);
    return std::nullopt;
  }

  template <typename Body>
  void prepare(http::request<Body>& req, const HttpRequest& spec) {
    req.method_string(spec.method);
    req.target(spec.target);
    req.version(11);
    req.set(http::field::host, host + ":" + port);
    req.set(http::field::user_agent, user_agent);
    req.keep_alive(true);
    if (!spec.content_type.empty()) req.set(http::field::content_type, spec.content_type);
    for (const auto& [name, value] : spec.headers) req.set(name, value);
  }

  // One attempt on the current connection. `stale` is set when the failure means a reused connection had been
  // closed by the server before our request reached it (safe to resend).
  template <typename Body>
  Result<HttpReply> attempt(http::request<Body>& req, const HttpRequest& spec, bool* stale) {
    *stale = false;
    stream->expires_after(request_timeout);
    beast::error_code ec = run([&](auto handler) { http::async_write(*stream, req, handler); });
    if (ec) {
      *stale = reused && ec != beast::error::timeout;
      return error(ec == beast::error::timeout ? ErrorCode::kTimeout : ErrorCode::kConnection,
                   "sending the request failed: " + ec.message());
    }
    HttpReply reply;
    bool got_some = false;
    bool keep_alive = false;
    if (spec.reply_file.empty()) {
      http::response_parser<http::string_body> parser;
      parser.body_limit(kMaxReplyBytes);
      ec = run([&](auto handler) { http::async_read(*stream, buffer, parser, handler); });
      got_some = parser.got_some();
      if (!ec) {
        auto& res = parser.get();
        reply.status = static_cast<int>(res.result_int());
        for (const auto& f : res) reply.headers[lower(std::string(f.name_string()))] = std::string(f.value());
        reply.body = std::move(res.body());
        keep_alive = res.keep_alive();
      }
    } else {
      http::response_parser<http::file_body> parser;
      parser.body_limit(std::numeric_limits<std::uint64_t>::max());  // not boost::none: Boost 1.74 reads it as 0
      beast::error_code open_ec;
      parser.get().body().open(spec.reply_file.c_str(), beast::file_mode::write, open_ec);
      if (open_ec) return error(ErrorCode::kIo, "cannot write " + spec.reply_file + ": " + open_ec.message());
      ec = run([&](auto handler) { http::async_read(*stream, buffer, parser, handler); });
      got_some = parser.got_some();
      parser.get().body().close();
      if (!ec) {
        auto& res = parser.get();
        reply.status = static_cast<int>(res.result_int());
        for (const auto& f : res) reply.headers[lower(std::string(f.name_string()))] = std::string(f.value());
        keep_alive = res.keep_alive();
        if (reply.status < 200 || reply.status >= 300) {
          std::ifstream in(spec.reply_file, std::ios::binary);
          std::stringstream ss;
          ss << in.rdbuf();
          reply.body = ss.str();
        }
      }
    }
    if (ec) {
      *stale = reused && !got_some && ec != beast::error::timeout;
      return error(ec == beast::error::timeout ? ErrorCode::kTimeout : ErrorCode::kConnection,
                   ec == beast::error::timeout ? "no answer within the request timeout"
                                               : "reading the answer failed: " + ec.message());
    }
    reused = true;
    if (!keep_alive) close();
    return reply;
  }

  // One attempt with a freshly built request (a file body is reopened, so a resend starts at its beginning).
  Result<HttpReply> attempt(const HttpRequest& spec, bool* stale) {
    if (spec.body_file.empty()) {
      http::request<http::string_body> req;
      prepare(req, spec);
      req.body() = spec.body;
      if (!spec.body.empty() || spec.method == "POST" || spec.method == "PUT") req.prepare_payload();
      return attempt(req, spec, stale);
    }
    http::request<http::file_body> req;
    prepare(req, spec);
    beast::error_code ec;
    req.body().open(spec.body_file.c_str(), beast::file_mode::scan, ec);
    if (ec) return error(ErrorCode::kInvalidArgument, "cannot read " + spec.body_file + ": " + ec.message());
    req.prepare_payload();
    return attempt(req, spec, stale);
  }
};

HttpConnection::HttpConnection(std::string host, std::string port, std::chrono::milliseconds connect_timeout,
                               std::chrono::milliseconds request_timeout, std::string user_agent)
    : impl_(std::make_unique<Impl>()) {
  impl_->host = std::move(host);
  impl_->port = std::move(port);
  impl_->connect_timeout = connect_timeout;
  impl_->request_timeout = request_timeout;
  impl_->user_agent = std::move(user_agent);
}

HttpConnection::~HttpConnection() {
  if (impl_) impl_->close();
}

Result<HttpReply> HttpConnection::exchange(const HttpRequest& spec, std::stop_token stop) {
  const auto stopped = [&] {
    impl_->close();
    return error(ErrorCode::kStopped, spec.method + " " + spec.target + ": stopped");
  };
  impl_->stop = std::move(stop);
  for (int round = 0; round < 2; ++round) {
    if (impl_->stop.stop_requested()) return stopped();
    if (!impl_->stream) {
      if (auto e = impl_->connect()) return impl_->stop.stop_requested() ? stopped() : *e;
    }
    bool stale = false;
    Result<HttpReply> r = impl_->attempt(spec, &stale);
    if (r.ok()) return r;
    impl_->close();
    if (impl_->stop.stop_requested()) return stopped();
    if (!stale) return r;
  }
  return error(ErrorCode::kConnection, "the connection was closed twice in a row");
}

}  // namespace texwarp::client
