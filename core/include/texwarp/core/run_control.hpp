// RunControl: how a long computation runs and is watched: worker threads, a progress callback called between
// tiles, and a cancellation flag checked between tiles (CanceledError when set).
#pragma once

#include <atomic>
#include <functional>
#include <stdexcept>

namespace texwarp {

struct RunControl {
  int threads = 0;                                // 0: all hardware threads
  std::function<void(double fraction)> progress;  // 0..1, from worker threads, serialised
  const std::atomic<bool>* cancel = nullptr;      // set to stop at the next tile

  int thread_count() const;
  bool canceled() const { return cancel != nullptr && cancel->load(std::memory_order_relaxed); }
};

class CanceledError : public std::runtime_error {
 public:
  CanceledError() : std::runtime_error("canceled") {}
};

}  // namespace texwarp
