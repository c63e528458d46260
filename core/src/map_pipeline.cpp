// A texture set's maps through one output grid in turn: see map_pipeline.hpp.
#include "texwarp/core/map_pipeline.hpp"

#include <chrono>
#include <future>
#include <optional>
#include <utility>

namespace texwarp {

std::vector<double> run_map_pipeline(std::size_t count, const MapPipelineSteps& steps) {
  std::vector<double> waited;
  std::optional<Image> next;
  for (std::size_t i = 0; i < count; ++i) {
    Image source = next ? std::move(*next) : steps.decode(i);
    next.reset();
    const Image output = steps.sample(i, std::move(source));
    if (i + 1 == count) {
      const auto start = std::chrono::steady_clock::now();
      steps.write(i, output);
      waited.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      break;
    }
    std::future<void> writing = std::async(std::launch::async, [&steps, &output, i] { steps.write(i, output); });
    try {
      next = steps.decode(i + 1);
    } catch (...) {
      writing.wait();  // the write's own failure, if any, is dropped for the decode's
      throw;
    }
    const auto start = std::chrono::steady_clock::now();
    writing.get();
    waited.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return waited;
}

double waited_share(double worked, double waited) { return worked > waited && worked > 0.0 ? waited / worked : 1.0; }

}  // namespace texwarp
