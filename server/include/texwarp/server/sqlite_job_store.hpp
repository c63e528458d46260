// SqliteJobStore: the JobStore of one node, in `<data-dir>/jobs.sqlite3` (WAL, synchronous=FULL: an acknowledged
// row survives a crash). Migrated to the newest schema when opened. One writer and one reader connection, each
// behind its own lock; every write is one short transaction.
#pragma once

#include <chrono>
#include <filesystem>
#include <mutex>
#include <string>
#include <type_traits>

#include "texwarp/server/job_store.hpp"
#include "texwarp/server/sqlite_connection.hpp"

namespace texwarp::server {

class SqliteJobStore final : public JobStore {
 public:
  // Opens (creating it when missing) and migrates the file. Throws std::runtime_error naming the file when it cannot
  // be opened, is not a job store, or has a schema newer than this build's.
  explicit SqliteJobStore(const std::filesystem::path& file);

  std::string backend() const override { return "sqlite"; }
  int schema_version() override;

  Inserted insert(const NewJob& job) override;
  std::vector<Inserted> insert_batch(const std::vector<NewJob>& jobs) override;

  std::optional<JobRow> get(const std::string& id) override;
  std::optional<JobRow> find_by_idempotency_key(const std::string& key) override;
  std::optional<std::string> spec_json(const std::string& id) override;
  std::vector<JobRow> list(const ListQuery& query) override;

  std::optional<Lease> claim(const std::string& node_id, std::int64_t now_ms, std::int64_t lease_ms) override;
  Renewal renew(const std::string& id, std::int64_t epoch, int progress, std::int64_t now_ms,
                std::int64_t lease_ms) override;
  bool finish(const std::string& id, std::int64_t epoch, proto::JobState state, std::int64_t now_ms, int progress,
              const std::string& error_json, const std::string& result_json, const std::string& result_folder) override;
  bool release(const std::string& id, std::int64_t epoch) override;
  CancelOutcome request_cancel(const std::string& id, std::int64_t now_ms) override;
  Reclaimed reclaim_expired(std::int64_t now_ms, int max_attempts,
                            const std::optional<std::string>& node_id = std::nullopt) override;

  PurgeOutcome purge(const std::string& id) override;
  std::vector<std::string> delete_finished_before(std::int64_t cutoff_ms) override;

  std::int64_t count(proto::JobState state) override;
  FinishedSince finished_since(std::int64_t since_ms) override;

  void register_node(const NodeInfo& node) override;
  void heartbeat_node(const std::string& node_id, std::int64_t now_ms, int running) override;
  void remove_node(const std::string& node_id) override;
  std::vector<NodeInfo> nodes() override;

  std::unique_ptr<MaintenanceLock> try_maintenance_lock() override;

  std::string health() override;

 private:
  // Runs `f` (a write on writer_) under the write lock and remembers whether it failed, for health().
  template <class F>
  std::invoke_result_t<F&> write(F&& f) {
    std::lock_guard lock(write_mutex_);
    try {
      if constexpr (std::is_void_v<std::invoke_result_t<F&>>) {
        f();
        note_write({});
      } else {
        auto result = f();
        note_write({});
        return result;
      }
    } catch (const std::exception& e) {
      note_write(e.what());
      throw;
    }
  }
  Inserted insert_locked(const NewJob& job);  // inside a transaction on writer_
  void note_write(const std::string& error);
  std::string write_error();

  std::filesystem::path file_;
  std::mutex write_mutex_;
  SqliteConnection writer_;
  std::mutex read_mutex_;
  SqliteConnection reader_;
  std::mutex health_mutex_;
  std::string write_error_;                                   // what the last write threw; empty when it succeeded
  std::chrono::steady_clock::time_point last_write_probe_{};  // health()'s last trial write (under health_mutex_)
};

}  // namespace texwarp::server
