// JobStore: the durable record of every accepted job, and the queue itself: one interface, two implementations
// (SqliteJobStore: one node, the embedded default; PostgresJobStore: any number of nodes sharing one database).
// Rows hold state, priority, labels, attempts, timestamps, the canonical job JSON, idempotency key, body fingerprint,
// the error or result manifest, and the lease of a running job: the node that holds it, its expiry, and its epoch —
// the fencing token that every write about a running job must present (a node whose lease expired and was taken
// over can never record an outcome). Implementations are thread-safe; a full disk is std::system_error (ENOSPC);
// a lost database connection is StoreUnavailable (the caller retries; nothing is half-written).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/job_status.hpp"

namespace texwarp::server {

using Labels = std::map<std::string, std::string>;

struct JobRow {
  std::int64_t seq = 0;  // insertion order (pagination, FIFO within a priority)
  std::string id;
  std::string name;
  proto::JobKind kind = proto::JobKind::kImage;
  proto::JobState state = proto::JobState::kQueued;
  int priority = 0;  // higher runs first
  Labels labels;
  int progress = 0;  // percent, as last stored (a running job's holder stores it with each heartbeat)
  int attempts = 0;  // claims so far (each expired or crashed lease counts)
  bool cancel_requested = false;
  std::int64_t created_ms = 0;
  std::optional<std::int64_t> started_ms;
  std::optional<std::int64_t> finished_ms;
  std::string error_json;     // problem JSON when failed
  std::string result_json;    // result manifest JSON when succeeded
  std::string result_folder;  // succeeded: the folder under results/ its files are served from ("" otherwise)
  std::string body_sha256;
  std::string node_id;           // the node that holds (running) or last held the lease; "" when never claimed
  std::int64_t lease_epoch = 0;  // incremented by every claim: the fencing token of the current/last lease
  std::optional<std::int64_t> lease_expires_ms;  // running only
};

struct NewJob {
  std::string id;
  std::string name;
  proto::JobKind kind = proto::JobKind::kImage;
  int priority = 0;
  Labels labels;
  std::string spec_json;    // canonical job JSON
  std::string body_sha256;  // fingerprint of the request body (idempotency)
  std::optional<std::string> idempotency_key;
  std::int64_t created_ms = 0;
};

// insert's answer: the row stored, or, when the idempotency key existed already, that job's row (nothing inserted).
struct Inserted {
  JobRow row;
  bool existed = false;
};

struct ListQuery {
  std::optional<std::int64_t> before_seq;  // rows with seq < this (the cursor)
  int limit = 50;
  std::optional<proto::JobState> state;
  Labels labels;  // every pair must match
};

// finished_since's answer: the queue's recent throughput and the time it was observed over.
struct FinishedSince {
  std::int64_t count = 0;                 // jobs that finished (any terminal state) in the window
  std::optional<std::int64_t> oldest_ms;  // the earliest finished_ms among them (nullopt when count is 0)
};

// A claimed job: run it, renew the lease, present `epoch` with every write about it.
struct Lease {
  std::string job_id;
  std::int64_t epoch = 0;
  int attempt = 0;  // attempts after this claim (1 for a first run)
  std::string spec_json;
};

// What a heartbeat learnt.
struct Renewal {
  bool held = false;  // false: the lease was lost (expired and reclaimed, or the job purged): stop, record nothing
  bool cancel_requested = false;  // someone asked, on any node
};

enum class CancelOutcome { kNotFound, kCanceled, kRequested, kAlreadyFinal };
enum class PurgeOutcome { kNotFound, kNotFinished, kPurged };

// What reclaim_expired() did with running jobs whose lease had expired.
struct Reclaimed {
  std::vector<std::string> requeued;  // queued again (attempts left)
  int canceled = 0;                   // a cancel had been requested
  int failed = 0;                     // attempts exhausted (kAttemptsExhausted problem recorded)
};

struct NodeInfo {
  std::string id;       // --node-id (default: hostname:port)
  std::string address;  // where its API listens, as it was told (HOST:PORT)
  std::string version;
  int workers = 0;
  std::int64_t pid = 0;
  std::int64_t started_ms = 0;
  std::int64_t last_seen_ms = 0;  // its last heartbeat
  int running = 0;                // jobs it holds leases on, as of its last heartbeat
};

// The database cannot be reached (connection lost, server restarting): retry later; nothing was changed.
class StoreUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Held while one node runs maintenance (retention, temp clean-up); released when destroyed.
class MaintenanceLock {
 public:
  virtual ~MaintenanceLock() = default;
};

class JobStore {
 public:
  virtual ~JobStore() = default;
  JobStore() = default;
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  // "sqlite" or "postgresql".
  virtual std::string backend() const = 0;
  // The schema version the store is at, and the newest this build knows.
  virtual int schema_version() = 0;
  static constexpr int kSchemaVersion = 2;

  // Inserts the job (state queued); with an idempotency key that exists already, inserts nothing and returns that
  // job. Two nodes inserting the same key at once make one job.
  virtual Inserted insert(const NewJob& job) = 0;
  // All or nothing, in one transaction; the answers in order.
  virtual std::vector<Inserted> insert_batch(const std::vector<NewJob>& jobs) = 0;

  virtual std::optional<JobRow> get(const std::string& id) = 0;
  // The job inserted with this idempotency key (a batch's job i has "<key> #<i>"), if any.
  virtual std::optional<JobRow> find_by_idempotency_key(const std::string& key) = 0;
  virtual std::optional<std::string> spec_json(const std::string& id) = 0;
  // Newest first.
  virtual std::vector<JobRow> list(const ListQuery& query) = 0;

  // The queued job to run next (highest priority, then oldest) → running, leased to `node_id` until now + lease_ms,
  // attempts + 1, lease_epoch + 1. A short transaction (FOR UPDATE SKIP LOCKED on PostgreSQL): nodes claiming at
  // once never get the same job. nullopt when nothing is queued.
  virtual std::optional<Lease> claim(const std::string& node_id, std::int64_t now_ms, std::int64_t lease_ms) = 0;
  // Extends the lease to now + lease_ms and stores progress, when `epoch` is still the job's and it is running.
  virtual Renewal renew(const std::string& id, std::int64_t epoch, int progress, std::int64_t now_ms,
                        std::int64_t lease_ms) = 0;
  // running → succeeded | failed | canceled with its error, result manifest and result folder, when `epoch` is still
  // the job's and it is running. False when fenced (nothing written): the caller discards what it produced.
  virtual bool finish(const std::string& id, std::int64_t epoch, proto::JobState state, std::int64_t now_ms,
                      int progress, const std::string& error_json, const std::string& result_json,
                      const std::string& result_folder) = 0;
  // running → queued, the attempt given back (a graceful shutdown), when `epoch` is still the job's.
  virtual bool release(const std::string& id, std::int64_t epoch) = 0;
  // Queued → canceled now; running → cancel_requested (its holder sees it at its next heartbeat).
  virtual CancelOutcome request_cancel(const std::string& id, std::int64_t now_ms) = 0;

  // Running jobs whose lease expired before now_ms (or, with `node_id`, every running job leased to that node: it
  // restarted, so its leases are dead): cancel requested → canceled; attempts ≥ max_attempts → failed; else queued.
  virtual Reclaimed reclaim_expired(std::int64_t now_ms, int max_attempts,
                                    const std::optional<std::string>& node_id = std::nullopt) = 0;

  // Deletes a finished job's row (its files are the caller's).
  virtual PurgeOutcome purge(const std::string& id) = 0;
  // Deletes finished jobs finished before `cutoff_ms`; returns their ids (their files are the caller's).
  virtual std::vector<std::string> delete_finished_before(std::int64_t cutoff_ms) = 0;

  virtual std::int64_t count(proto::JobState state) = 0;
  // Jobs that finished (any terminal state) at or after `since_ms`, and the earliest of their finished_ms: the
  // queue's recent throughput.
  virtual FinishedSince finished_since(std::int64_t since_ms) = 0;

  // Node registry: a node registers at start, heartbeats (running count), and leaves at a clean shutdown.
  virtual void register_node(const NodeInfo& node) = 0;
  virtual void heartbeat_node(const std::string& node_id, std::int64_t now_ms, int running) = 0;
  virtual void remove_node(const std::string& node_id) = 0;
  virtual std::vector<NodeInfo> nodes() = 0;

  // The maintenance lock (a PostgreSQL advisory lock; always granted on SQLite's single node), or nullptr when
  // another node holds it.
  virtual std::unique_ptr<MaintenanceLock> try_maintenance_lock() = 0;

  // "ok" when a read works and so does a write (tried again, at most every 2 s, when the last one failed), else
  // "failing: <why>".
  virtual std::string health() = 0;
  bool healthy() { return health() == "ok"; }
};

}  // namespace texwarp::server
