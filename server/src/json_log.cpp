// Structured JSON logs: see json_log.hpp.
#include "texwarp/server/json_log.hpp"

#include <atomic>
#include <cstdio>
#include <mutex>
#include <stdexcept>

#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {
namespace {

std::atomic<int> g_level{static_cast<int>(LogLevel::kInfo)};
std::mutex g_mutex;

const char* level_name(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug:
      return "debug";
    case LogLevel::kInfo:
      return "info";
    case LogLevel::kWarn:
      return "warn";
    case LogLevel::kError:
      return "error";
  }
  return "info";
}

}  // namespace

LogLevel parse_log_level(const std::string& name) {
  for (LogLevel l : {LogLevel::kDebug, LogLevel::kInfo, LogLevel::kWarn, LogLevel::kError}) {
    if (name == level_name(l)) return l;
  }
  throw std::invalid_argument("unknown log level \"" + name + "\" (debug, info, warn or error)");
}

void set_log_level(LogLevel level) { g_level.store(static_cast<int>(level)); }

bool log_enabled(LogLevel level) { return static_cast<int>(level) >= g_level.load(std::memory_order_relaxed); }

void log_event(LogLevel level, std::string_view msg, nlohmann::json fields) {
  if (!log_enabled(level)) return;
  nlohmann::ordered_json line;
  line["ts"] = rfc3339_utc(now_ms());
  line["level"] = level_name(level);
  line["msg"] = msg;
  if (fields.is_object()) {
    for (const auto& [key, value] : fields.items()) line[key] = value;
  }
  const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  std::lock_guard lock(g_mutex);
  std::fwrite(text.data(), 1, text.size(), stderr);
  std::fflush(stderr);
}

}  // namespace texwarp::server
