// HttpServer: the Beast/Asio side of texwarpd: accepts connections (at most max_connections in all and
// max_connections_per_client from one address; at the cap idle keep-alive connections are closed, oldest first,
// and probes are still answered), reads each request's header first so the router can refuse it before any body is
// read, receives bodies into memory or (blob uploads) straight into a file, hands requests that parse or store a
// body to a small pool off the I/O threads, enforces read/write/idle timeouts, and logs and counts every request.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <memory>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/thread_pool.hpp>

#include "texwarp/server/api_router.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/server_config.hpp"

namespace texwarp::server {

class HttpServer {
 public:
  HttpServer(boost::asio::io_context& ioc, const ServerConfig& config, ApiRouter& router, Metrics& metrics,
             JobService& service);
  // Waits for the requests being handled off the I/O threads.
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Binds and listens on config.host:config.port and starts accepting; returns the bound port.
  // std::runtime_error when the address cannot be bound.
  unsigned short start();
  // Closes the listening socket (connections already open finish their current request).
  void stop_accepting();
  std::size_t connections() const { return connections_->load(); }

  struct Shared;  // what every connection uses

 private:
  void accept();
  void on_accept(boost::asio::ip::tcp::socket socket);
  // accept() failed (e.g. EMFILE: out of file descriptors): logged once per episode, retried after a backoff that
  // grows from 10 ms to 1 s, never in a hot loop.
  void on_accept_error(const boost::system::error_code& ec);

  boost::asio::io_context& ioc_;
  boost::asio::thread_pool pool_;  // handlers that parse, decode or store a body (POST /v1/jobs, /v1/blobs)
  boost::asio::ip::tcp::acceptor acceptor_;
  boost::asio::steady_timer accept_timer_;
  std::chrono::milliseconds accept_backoff_{0};
  bool accept_failing_ = false;
  std::shared_ptr<Shared> shared_;
  std::shared_ptr<std::atomic<std::size_t>> connections_;
};

}  // namespace texwarp::server
