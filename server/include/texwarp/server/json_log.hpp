// Structured logs: one JSON object per line on stderr ({"ts", "level", "msg", ...fields}), e.g. the job id
// in "job" and the request id in "request_id", so that a log shipper can index them. Thread-safe.
#pragma once

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace texwarp::server {

enum class LogLevel { kDebug, kInfo, kWarn, kError };

LogLevel parse_log_level(const std::string& name);  // debug | info | warn | error
void set_log_level(LogLevel level);
bool log_enabled(LogLevel level);

// Writes {"ts": RFC 3339, "level", "msg", ...fields} when `level` is enabled. `fields` must be an object (or null).
void log_event(LogLevel level, std::string_view msg, nlohmann::json fields = nullptr);

}  // namespace texwarp::server
