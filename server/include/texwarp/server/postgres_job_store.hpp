// PostgresJobStore: the JobStore that any number of nodes share, in one PostgreSQL database (libpqxx). Versioned
// migrations (table texwarp_schema); claims with FOR UPDATE SKIP LOCKED; every write about a running job fenced by
// its lease epoch; the maintenance lock a session advisory lock. A small pool of connections: a call borrows one,
// and a connection that broke is dropped (the call throws StoreUnavailable) and a new one is opened next time.
#pragma once

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "texwarp/server/job_store.hpp"

namespace texwarp::server {

struct PgConnection;  // a libpqxx connection (postgres_job_store.cpp)

class PostgresJobStore final : public JobStore {
 public:
  // Connects to `url` (a libpq URI: postgresql://…) and checks the schema: with `migrate`, creates or upgrades it;
  // without, throws std::runtime_error when it is older than this build's ("run texwarpd --store … --migrate").
  // An unreachable server or a bad URL: std::runtime_error naming the store (never its password).
  PostgresJobStore(const std::string& url, bool migrate, int max_connections = 8);
  ~PostgresJobStore() override;

  // Brings the schema at `url` to `version` (≤ kSchemaVersion; tests make older ones) and returns the version it is
  // at. Nodes migrating at once take turns (an advisory lock), and each step is one transaction.
  static int migrate(const std::string& url, int version = kSchemaVersion);
  // The URL without its password, for messages and logs.
  static std::string redacted(const std::string& url);

  std::string backend() const override { return "postgresql"; }
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
  class Borrowed;
  // Runs `f(connection)` on a borrowed connection; a broken connection is dropped and becomes StoreUnavailable.
  // `write`: remembered for health().
  template <class F>
  auto with_connection(bool write, F&& f);
  std::unique_ptr<PgConnection> open_connection() const;

  std::string url_;       // with the connection options this store adds
  std::string redacted_;  // for messages
  int max_connections_;
  std::mutex pool_mutex_;
  std::condition_variable pool_returned_;
  std::vector<std::unique_ptr<PgConnection>> idle_;
  int borrowed_ = 0;
  std::mutex health_mutex_;
  std::string write_error_;  // what the last write threw; empty when it succeeded
  std::chrono::steady_clock::time_point last_write_probe_{};
};

}  // namespace texwarp::server
