// WorkSignal: the local wake-up of idle workers. The job store is the queue; a worker that found nothing to claim
// sleeps until a job is submitted on this node (notify) or --poll-ms passes (jobs submitted on other nodes), or the
// signal is closed (shutdown).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace texwarp::server {

class WorkSignal {
 public:
  // Something may be claimable: wakes every waiting worker.
  void notify() {
    {
      std::lock_guard lock(mutex_);
      ++generation_;
    }
    cv_.notify_all();
  }
  // Waits until notify() or close() after the call, or `timeout`.
  template <class Rep, class Period>
  void wait_for(std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock lock(mutex_);
    const std::uint64_t seen = generation_;
    cv_.wait_for(lock, timeout, [&] { return closed_ || generation_ != seen; });
  }
  void close() {
    {
      std::lock_guard lock(mutex_);
      closed_ = true;
    }
    cv_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::uint64_t generation_ = 0;
  bool closed_ = false;
};

}  // namespace texwarp::server
