// Row bands on the run's threads: see row_bands.hpp.
#include "texwarp/core/row_bands.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace texwarp {

void for_each_row_band(int height, const RunControl& control, const std::function<void(int, int)>& band) {
  if (height <= 0) return;
  constexpr int kBandRows = 16;
  const int bands = (height + kBandRows - 1) / kBandRows;
  const int threads = std::max(1, std::min(control.thread_count(), bands));
  std::atomic<int> next{0};
  std::atomic<bool> stop{false};
  std::exception_ptr failure;
  std::mutex mutex;
  auto worker = [&] {
    while (!stop.load(std::memory_order_relaxed)) {
      const int b = next.fetch_add(1);
      if (b >= bands) return;
      try {
        if (control.canceled()) throw CanceledError();
        band(b * kBandRows, std::min(height, (b + 1) * kBandRows));
      } catch (...) {
        std::lock_guard lock(mutex);
        if (!failure) failure = std::current_exception();
        stop = true;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace texwarp
