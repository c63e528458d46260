// The CPU reference backend: batches of points integrated in parallel: see cpu_backend.hpp.
#include "texwarp/core/cpu_backend.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace texwarp {
namespace {

// Points sharing one step sequence: neighbouring pixels of a row, or consecutive points of a list.
constexpr std::size_t kBatch = 64;

}  // namespace

void CpuBackend::flow_points(const WarpProblem& problem, std::span<Point> points, Direction direction,
                             const RunControl& control) {
  if (points.empty() || problem.field_is_zero()) {
    if (control.progress) control.progress(1.0);
    return;
  }
  const VelocityField field(problem);
  const std::size_t batches = (points.size() + kBatch - 1) / kBatch;
  const int threads = static_cast<int>(std::min<std::size_t>(control.thread_count(), batches));

  std::atomic<std::size_t> next{0};
  std::atomic<std::size_t> done{0};
  std::atomic<bool> stop{false};
  std::exception_ptr failure;
  std::mutex mutex;  // guards failure and serialises progress callbacks

  auto worker = [&] {
    while (!stop.load(std::memory_order_relaxed)) {
      const std::size_t b = next.fetch_add(1);
      if (b >= batches) break;
      try {
        if (control.canceled()) throw CanceledError();
        const std::size_t begin = b * kBatch;
        const std::size_t end = std::min(points.size(), begin + kBatch);
        integrate_pathlines(field, points.subspan(begin, end - begin), direction, problem.tolerance_px());
        const std::size_t finished = done.fetch_add(1) + 1;
        if (control.progress) {
          std::lock_guard lock(mutex);
          control.progress(static_cast<double>(finished) / static_cast<double>(batches));
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
  for (auto& th : pool) th.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace texwarp
