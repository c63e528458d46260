// Chunks of work on the run's threads: see parallel_chunks.hpp.
#include "texwarp/core/parallel_chunks.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace texwarp {

void for_each_chunk(std::size_t count, std::size_t chunk, const RunControl& control,
                    const std::function<void(std::size_t, std::size_t)>& body, bool report_progress) {
  if (count == 0) return;
  const std::size_t chunks = (count + chunk - 1) / chunk;
  const int threads = static_cast<int>(std::min<std::size_t>(std::max(1, control.thread_count()), chunks));
  std::atomic<std::size_t> next{0};
  std::size_t done = 0;  // chunks finished, counted under `mutex`: a later report never shows fewer
  std::atomic<bool> stop{false};
  std::exception_ptr failure;
  std::mutex mutex;  // guards failure and serialises progress callbacks
  auto worker = [&] {
    while (!stop.load(std::memory_order_relaxed)) {
      const std::size_t c = next.fetch_add(1);
      if (c >= chunks) return;
      try {
        if (control.canceled()) throw CanceledError();
        const std::size_t begin = c * chunk;
        body(begin, std::min(count, begin + chunk));
        if (report_progress && control.progress) {
          std::lock_guard lock(mutex);
          control.progress(static_cast<double>(++done) / static_cast<double>(chunks));
        }
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

void for_each_row_band(int height, const RunControl& control, const std::function<void(int, int)>& band) {
  constexpr std::size_t kBandRows = 16;
  if (height <= 0) return;
  for_each_chunk(static_cast<std::size_t>(height), kBandRows, control,
                 [&](std::size_t begin, std::size_t end) { band(static_cast<int>(begin), static_cast<int>(end)); });
}

}  // namespace texwarp
