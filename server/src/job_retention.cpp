// What the data folder keeps: see job_retention.hpp.
#include "texwarp/server/job_retention.hpp"

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "texwarp/server/json_log.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;

constexpr double kOrphanSweepS = 300.0;  // orphans of dead nodes go at most this long after their leases

// Whether the folder `name` under results/ is still of use (see job_retention.hpp for the rule).
bool keep(JobStore& store, const std::string& name) {
  const ResultFolderName parsed = ResultFolders::parse(name);
  if (parsed.kind == ResultFolderName::Kind::kOther) return false;
  const auto row = store.get(parsed.job_id);
  if (!row) return false;
  if (row->state == proto::JobState::kSucceeded) return row->result_folder == name;
  const bool live_run = row->state == proto::JobState::kRunning && row->lease_epoch == parsed.epoch;
  return live_run && parsed.kind != ResultFolderName::Kind::kLegacy;
}

}  // namespace

JobRetention::JobRetention(const ServerConfig& config, JobStore& store, const ResultFolders& results, StopSignal& stop)
    : config_(config), store_(store), results_(results), stop_(stop) {}

std::size_t JobRetention::remove_orphans() {
  const auto lock = store_.try_maintenance_lock();
  if (!lock) return 0;  // another node does it now
  return remove_orphans_locked();
}

std::size_t JobRetention::remove_orphans_locked() {
  std::size_t orphans = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(results_.root(), ec)) {
    const std::string name = entry.path().filename().string();
    if (keep(store_, name)) continue;
    std::error_code rec;
    if (fs::remove_all(entry.path(), rec) > 0) ++orphans;
  }
  return orphans;
}

std::size_t JobRetention::delete_expired_locked() {
  const auto cutoff = now_ms() - static_cast<std::int64_t>(config_.retention_hours * 3600e3);
  // The rows go first, then their folders: a folder whose row is gone is an orphan anyway.
  const std::vector<std::string> ids = store_.delete_finished_before(cutoff);
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(results_.root(), ec)) {
    const ResultFolderName parsed = ResultFolders::parse(entry.path().filename().string());
    if (std::find(ids.begin(), ids.end(), parsed.job_id) == ids.end()) continue;
    std::error_code rec;
    fs::remove_all(entry.path(), rec);
  }
  return ids.size();
}

void JobRetention::start() {
  sweep_ = std::thread([this] { sweep_main(); });
}

void JobRetention::join() {
  if (sweep_.joinable()) sweep_.join();
}

void JobRetention::sweep_main() {
  const double retention_period = config_.retention_hours > 0.0 ? config_.retention_hours * 360.0 : kOrphanSweepS;
  const auto period = std::chrono::duration<double>(std::clamp(retention_period, 1.0, kOrphanSweepS));
  do {
    try {
      const auto lock = store_.try_maintenance_lock();
      if (!lock) continue;  // another node sweeps now
      if (config_.retention_hours > 0.0) {
        if (const std::size_t n = delete_expired_locked(); n > 0) {
          log_event(LogLevel::kInfo, "retention: deleted finished jobs", {{"count", n}});
        }
      }
      if (const std::size_t n = remove_orphans_locked(); n > 0) {
        log_event(LogLevel::kInfo, "removed orphaned result folders", {{"count", n}});
      }
    } catch (const std::exception& e) {
      log_event(LogLevel::kError, "maintenance sweep failed", {{"error", e.what()}});
    }
  } while (!stop_.wait_for(period));
}

}  // namespace texwarp::server
