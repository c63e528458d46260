// Retry-After from the queue's throughput: see retry_after.hpp.
#include "texwarp/server/retry_after.hpp"

#include <algorithm>
#include <cmath>

namespace texwarp::server {

double observed_seconds(std::int64_t now_ms, std::int64_t node_started_ms,
                        std::optional<std::int64_t> oldest_finished_ms, std::int64_t window_ms) {
  const std::int64_t since = oldest_finished_ms ? std::min(node_started_ms, *oldest_finished_ms) : node_started_ms;
  const std::int64_t seen_ms = std::min(window_ms, now_ms - since);
  return std::max(static_cast<double>(seen_ms) / 1000.0, kMinObservedS);
}

std::optional<int> retry_after_from_throughput(std::int64_t queued, std::int64_t finished, double observed_s) {
  if (finished < kMinFinishedForRate || !(observed_s > 0.0) || !std::isfinite(observed_s)) return std::nullopt;
  const double per_second = static_cast<double>(finished) / observed_s;
  const double s = std::ceil(static_cast<double>(std::max<std::int64_t>(queued, 0)) / per_second);
  return static_cast<int>(std::clamp(s, 1.0, static_cast<double>(kMaxRetryAfterS)));
}

}  // namespace texwarp::server
