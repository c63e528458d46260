// The CPU reference backend: batches of points integrated in parallel: see cpu_backend.hpp.
#include "texwarp/core/cpu_backend.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace texwarp {
namespace {

// Points sharing one step sequence: neighbouring pixels of a row, or consecutive points of a list.
constexpr std::size_t kBatch = 64;

// Runs integrate(begin, end) over batches of the n points on the control's threads, with progress and
// cancellation between batches; the first exception stops the others and is rethrown.
template <typename Integrate>
void for_each_batch(std::size_t n, const RunControl& control, Integrate&& integrate) {
  const std::size_t batches = (n + kBatch - 1) / kBatch;
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
        integrate(begin, std::min(n, begin + kBatch));
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

}  // namespace

void CpuBackend::flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                              Direction direction, const RunControl& control) {
  if (points.empty() || problem.segments().at(segment).field_is_zero) {
    if (control.progress) control.progress(1.0);
    return;
  }
  const VelocityField field(problem, segment);
  for_each_batch(points.size(), control, [&](std::size_t begin, std::size_t end) {
    integrate_pathlines(field, points.subspan(begin, end - begin), direction, problem.tolerance_px());
  });
}

void CpuBackend::flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                            std::span<FlowJacobian> jacobians, Direction direction,
                                            const RunControl& control) {
  if (jacobians.size() != points.size()) throw std::invalid_argument("flow_points_with_jacobian: sizes differ");
  const VelocityField field(problem, segment);
  for_each_batch(points.size(), control, [&](std::size_t begin, std::size_t end) {
    integrate_pathlines(field, points.subspan(begin, end - begin), jacobians.subspan(begin, end - begin), direction,
                        problem.tolerance_px());
  });
  if (points.empty() && control.progress) control.progress(1.0);
}

}  // namespace texwarp
