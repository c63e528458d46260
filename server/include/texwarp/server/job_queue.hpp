// JobQueue: job ids waiting for a worker, first in first out. Admission (the bounded length) is decided by the
// caller before push; pop blocks until an id arrives or the queue is closed.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>
#include <string>

namespace texwarp::server {

class JobQueue {
 public:
  void push(std::string id);
  // The next id, or nullopt once closed (ids still queued then stay in the store, re-queued at the next start).
  std::optional<std::string> pop();
  void close();
  std::size_t size() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::string> ids_;
  bool closed_ = false;
};

}  // namespace texwarp::server
