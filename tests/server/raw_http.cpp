// Plain HTTP/1.1 for tests over POSIX sockets: see raw_http.hpp.
#include "raw_http.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "test_time.hpp"

namespace texwarp::testing {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// Parses one complete reply at the front of `data`; returns its length, 0 if incomplete.
std::size_t parse_reply(const std::string& data, HttpReply* reply, bool eof, bool head) {
  const auto end = data.find("\r\n\r\n");
  if (end == std::string::npos) return 0;
  HttpReply r;
  std::size_t line_end = data.find("\r\n");
  const std::string status_line = data.substr(0, line_end);
  if (status_line.size() < 12) return 0;
  r.status = std::stoi(status_line.substr(9, 3));
  std::size_t pos = line_end + 2;
  while (pos < end) {
    const std::size_t next = data.find("\r\n", pos);
    const std::string line = data.substr(pos, next - pos);
    const auto colon = line.find(':');
    if (colon != std::string::npos) {
      std::string value = line.substr(colon + 1);
      value.erase(0, value.find_first_not_of(' '));
      r.headers[lower(line.substr(0, colon))] = value;
    }
    pos = next + 2;
  }
  const std::size_t body_start = end + 4;
  // No body: a reply to HEAD, and a 100, 204 or 304 without a Content-Length.
  const auto content_length = r.headers.find("content-length");
  const bool bodiless =
      head || (content_length == r.headers.end() && (r.status == 100 || r.status == 304 || r.status == 204));
  std::size_t length = 0;
  if (!bodiless) {
    if (content_length != r.headers.end()) {
      length = std::stoull(content_length->second);
    } else if (eof) {
      length = data.size() - body_start;
    } else {
      return 0;
    }
  }
  if (data.size() < body_start + length) return 0;
  r.body = data.substr(body_start, length);
  *reply = std::move(r);
  return body_start + length;
}

}  // namespace

nlohmann::json HttpReply::json() const {
  try {
    return nlohmann::json::parse(body);
  } catch (...) {
    return nullptr;
  }
}

std::string HttpReply::header(const std::string& name) const {
  const auto it = headers.find(lower(name));
  return it == headers.end() ? std::string() : it->second;
}

RawConnection::RawConnection(unsigned short port) {
  fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd_);
    throw std::runtime_error("cannot connect to 127.0.0.1:" + std::to_string(port));
  }
}

RawConnection::~RawConnection() {
  if (fd_ >= 0) ::close(fd_);
}

void RawConnection::send(const std::string& bytes) {
  head_ = bytes.rfind("HEAD ", 0) == 0;
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
    if (n <= 0) return;  // the server closed: the reply (if any) is read next
    done += static_cast<std::size_t>(n);
  }
}

HttpReply RawConnection::read_reply(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  HttpReply reply;
  bool eof = false;
  for (;;) {
    const std::size_t used = parse_reply(pending_, &reply, eof, head_);
    if (used > 0) {
      pending_.erase(0, used);
      if (reply.status == 100) {  // an interim answer: the real one follows
        reply = HttpReply{};
        continue;
      }
      return reply;
    }
    if (eof) return HttpReply{};
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return HttpReply{};
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return HttpReply{};
    char buf[65536];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    if (n <= 0) {
      eof = true;
    } else {
      pending_.append(buf, static_cast<std::size_t>(n));
    }
  }
}

HttpReply raw_exchange(unsigned short port, const std::string& bytes, double timeout_s) {
  RawConnection c(port);
  c.send(bytes);
  return c.read_reply(timeout_s);
}

constexpr double kReplyWaitSeconds = 60.0;

HttpReply http_request(unsigned short port, const std::string& method, const std::string& target,
                       const std::string& body, const Headers& headers, const std::string& content_type) {
  std::string req = method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n";
  if (!body.empty() || method == "POST") req += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  if (!content_type.empty() && (!body.empty() || method == "POST")) req += "Content-Type: " + content_type + "\r\n";
  for (const auto& [name, value] : headers) req.append(name).append(": ").append(value).append("\r\n");
  req += "\r\n" + body;
  // A reply is waited for as long as the work behind it may take on a loaded machine or under a sanitizer (a 32 MiB
  // body's parse took over 10 s there): a missing reply is still status 0, only later.
  return raw_exchange(port, req, wait_seconds(kReplyWaitSeconds));
}

}  // namespace texwarp::testing
