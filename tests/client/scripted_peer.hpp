// ScriptedPeer: an HTTP peer on loopback for client tests that answers the n-th connection with the n-th scripted
// reply and closes it (kHold: never answers, waits for the client to give up), recording when requests arrived and
// their request lines.
#pragma once

#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace texwarp::testing {

inline constexpr const char* kHold = "HOLD";

class ScriptedPeer {
 public:
  explicit ScriptedPeer(std::vector<std::string> replies);
  ~ScriptedPeer();
  ScriptedPeer(const ScriptedPeer&) = delete;
  ScriptedPeer& operator=(const ScriptedPeer&) = delete;

  int port() const { return port_; }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }
  std::vector<std::chrono::steady_clock::time_point> arrivals();
  int requests() { return static_cast<int>(arrivals().size()); }
  std::vector<std::string> request_lines();  // "GET /v1/jobs/x?wait=30 HTTP/1.1", in arrival order

 private:
  void serve();

  std::vector<std::string> replies_;
  int fd_ = -1;
  int port_ = 0;
  std::thread thread_;
  std::mutex mutex_;
  std::vector<std::chrono::steady_clock::time_point> arrivals_;
  std::vector<std::string> request_lines_;
};

// "HTTP/1.1 STATUS X" with Connection: close, the extra header lines (each ending in \r\n) and the body.
std::string scripted_reply(int status, const std::string& extra_headers = "", const std::string& body = "{}");

}  // namespace texwarp::testing
