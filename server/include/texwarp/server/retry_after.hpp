// Retry-After for a full queue from its recent throughput: the arithmetic alone (pure functions, no clock, no store),
// so that a young server's few seconds of history are divided by the seconds it has seen, not by the whole window.
#pragma once

#include <cstdint>
#include <optional>

namespace texwarp::server {

inline constexpr std::int64_t kThroughputWindowMs = std::int64_t{5} * 60 * 1000;  // finished jobs counted since
inline constexpr double kMinObservedS = 5.0;            // throughput is never taken over less time than this
inline constexpr std::int64_t kMinFinishedForRate = 3;  // fewer finished jobs are too few to estimate from
inline constexpr int kMaxRetryAfterS = 600;

// The seconds over which `finished_since(now − window)` was observed: now − the earlier of this node's start and the
// oldest finish in the window (nullopt: none), at most the window, at least kMinObservedS. All times epoch ms.
double observed_seconds(std::int64_t now_ms, std::int64_t node_started_ms,
                        std::optional<std::int64_t> oldest_finished_ms, std::int64_t window_ms = kThroughputWindowMs);

// ceil(queued / (finished / observed_s)) seconds, clamped to 1…kMaxRetryAfterS: the time the recent throughput takes
// to run the queued jobs. nullopt when fewer than kMinFinishedForRate jobs finished (the caller falls back) or
// observed_s is not a positive number.
std::optional<int> retry_after_from_throughput(std::int64_t queued, std::int64_t finished, double observed_s);

}  // namespace texwarp::server
