// StopSignal: the server's "stop" for its background threads (the workers' waits for storage, the retention
// sweep's sleep): set once, read without blocking, waited on with a timeout.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>

namespace texwarp::server {

class StopSignal {
 public:
  // Sets the signal and wakes every waiter; true when it was set already.
  bool set() {
    bool was_set = false;
    {
      std::lock_guard lock(mutex_);
      was_set = stopped_.exchange(true);
    }
    cv_.notify_all();
    return was_set;
  }
  bool is_set() const { return stopped_.load(); }
  // Waits up to `timeout`; true when the signal is set.
  template <class Rep, class Period>
  bool wait_for(std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock lock(mutex_);
    return cv_.wait_for(lock, timeout, [this] { return stopped_.load(); });
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::atomic<bool> stopped_{false};
};

}  // namespace texwarp::server
