// PausableProxy: a TCP relay on a free loopback port to 127.0.0.1:<target>, for a test that cuts one texwarpd node
// off from the database without touching the others: while paused it neither accepts nor forwards a byte (the
// node's database calls hang, as in a network partition); resume() delivers what waited.
#pragma once

#include <atomic>
#include <thread>

namespace texwarp::testing {

// A loopback TCP port nobody listens on at the moment (for a server the proxy is to relay to).
unsigned short free_loopback_port();

class PausableProxy {
 public:
  explicit PausableProxy(unsigned short target_port);
  ~PausableProxy();
  PausableProxy(const PausableProxy&) = delete;
  PausableProxy& operator=(const PausableProxy&) = delete;

  unsigned short port() const { return port_; }
  void pause() { paused_.store(true); }
  void resume() { paused_.store(false); }

 private:
  void relay();

  unsigned short target_port_;
  unsigned short port_ = 0;
  int listen_fd_ = -1;
  std::atomic<bool> paused_{false};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace texwarp::testing
