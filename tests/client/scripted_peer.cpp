// A scripted HTTP peer for client tests: see scripted_peer.hpp.
#include "scripted_peer.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <stdexcept>

namespace texwarp::testing {

ScriptedPeer::ScriptedPeer(std::vector<std::string> replies) : replies_(std::move(replies)) {
  fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof addr;
  if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd_, 8) != 0 ||
      ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    if (fd_ >= 0) ::close(fd_);
    throw std::runtime_error("ScriptedPeer: cannot listen on loopback");
  }
  port_ = ntohs(addr.sin_port);
  thread_ = std::thread([this] { serve(); });
}

ScriptedPeer::~ScriptedPeer() {
  ::shutdown(fd_, SHUT_RDWR);
  ::close(fd_);
  thread_.join();
}

std::vector<std::chrono::steady_clock::time_point> ScriptedPeer::arrivals() {
  std::lock_guard lock(mutex_);
  return arrivals_;
}

std::vector<std::string> ScriptedPeer::request_lines() {
  std::lock_guard lock(mutex_);
  return request_lines_;
}

void ScriptedPeer::serve() {
  for (const auto& reply : replies_) {
    const int conn = ::accept(fd_, nullptr, nullptr);
    if (conn < 0) return;
    std::string request;
    char buf[4096];
    while (request.find("\r\n\r\n") == std::string::npos) {
      const ssize_t n = ::recv(conn, buf, sizeof buf, 0);
      if (n <= 0) break;
      request.append(buf, static_cast<std::size_t>(n));
    }
    {
      std::lock_guard lock(mutex_);
      arrivals_.push_back(std::chrono::steady_clock::now());
      request_lines_.push_back(request.substr(0, request.find("\r\n")));
    }
    if (reply == kHold) {  // never answer: wait until the client gives up and closes
      while (::recv(conn, buf, sizeof buf, 0) > 0) {
      }
    }
    ::send(conn, reply.data(), reply.size(), MSG_NOSIGNAL);
    ::close(conn);  // each reply says Connection: close
  }
}

std::string scripted_reply(int status, const std::string& extra_headers, const std::string& body) {
  return "HTTP/1.1 " + std::to_string(status) +
         " X\r\nConnection: close\r\nContent-Length: " + std::to_string(body.size()) + "\r\n" + extra_headers + "\r\n" +
         body;
}

}  // namespace texwarp::testing
