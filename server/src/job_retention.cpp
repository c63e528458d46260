// What the data folder keeps: see job_retention.hpp.
#include "texwarp/server/job_retention.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "texwarp/server/job_id.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {

namespace fs = std::filesystem;

JobRetention::JobRetention(const ServerConfig& config, JobStore& store, const ResultFolders& results, StopSignal& stop)
    : config_(config), store_(store), results_(results), stop_(stop) {}

std::size_t JobRetention::remove_orphans() {
  // Half-written folders (never served) and folders of jobs the store no longer has (retention deleted the row,
  // then the process died).
  std::size_t orphans = 0;
  for (const auto& entry : fs::directory_iterator(results_.root())) {
    const std::string name = entry.path().filename().string();
    if (ResultFolders::is_temporary(name) || !is_job_id(name) || !store_.get(name)) {
      std::error_code ec;
      if (fs::remove_all(entry.path(), ec) > 0) ++orphans;
    }
  }
  return orphans;
}

void JobRetention::start() {
  if (config_.retention_hours > 0.0) sweep_ = std::thread([this] { sweep_main(); });
}

void JobRetention::join() {
  if (sweep_.joinable()) sweep_.join();
}

void JobRetention::sweep_main() {
  const auto period = std::chrono::duration<double>(std::clamp(config_.retention_hours * 360.0, 1.0, 3600.0));
  while (!stop_.is_set()) {
    try {
      const auto cutoff = now_ms() - static_cast<std::int64_t>(config_.retention_hours * 3600e3);
      const auto ids = store_.delete_finished_before(cutoff);
      for (const auto& id : ids) {
        std::error_code ec;
        fs::remove_all(results_.published(id), ec);
      }
      if (!ids.empty()) log_event(LogLevel::kInfo, "retention: deleted finished jobs", {{"count", ids.size()}});
    } catch (const std::exception& e) {
      log_event(LogLevel::kError, "retention sweep failed", {{"error", e.what()}});
    }
    stop_.wait_for(period);
  }
}

}  // namespace texwarp::server
