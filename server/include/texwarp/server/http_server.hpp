// HttpServer: the Beast/Asio side of texwarpd: accepts connections (at most max_connections; beyond that a 503),
// reads each request's header first so the router can refuse it before any body is read, receives bodies into
// memory or (blob uploads) straight into a file, enforces read/write/idle timeouts, keeps connections alive, and
// logs and counts every request. Handlers run on the I/O threads and are short; warps run on the service's workers.
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include "texwarp/server/api_router.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/server_config.hpp"

namespace texwarp::server {

class HttpServer {
 public:
  HttpServer(boost::asio::io_context& ioc, const ServerConfig& config, ApiRouter& router, Metrics& metrics,
             JobService& service);

  // Binds and listens on config.host:config.port and starts accepting; returns the bound port.
  // std::runtime_error when the address cannot be bound.
  unsigned short start();
  // Closes the listening socket (connections already open finish their current request).
  void stop_accepting();
  std::size_t connections() const { return connections_->load(); }

  struct Shared;  // what every connection uses

 private:
  void accept();

  boost::asio::io_context& ioc_;
  boost::asio::ip::tcp::acceptor acceptor_;
  std::shared_ptr<Shared> shared_;
  std::shared_ptr<std::atomic<std::size_t>> connections_;
};

}  // namespace texwarp::server
