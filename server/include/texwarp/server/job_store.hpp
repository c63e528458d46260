// JobStore: the durable record of every accepted job in SQLite (WAL, synchronous=FULL: an acknowledged job row
// survives a crash): state, attempts, timestamps, canonical job JSON, idempotency key, body fingerprint, error or
// result manifest. Thread-safe (one writer, one reader connection); a full disk is std::system_error (ENOSPC).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "texwarp/proto/job_status.hpp"
#include "texwarp/server/sqlite_connection.hpp"

namespace texwarp::server {

struct JobRow {
  std::int64_t seq = 0;  // insertion order (pagination)
  std::string id;
  std::string name;
  proto::JobKind kind = proto::JobKind::kImage;
  proto::JobState state = proto::JobState::kQueued;
  int progress = 0;  // as last stored (running jobs: see the worker's live value)
  int attempts = 0;
  bool cancel_requested = false;
  std::int64_t created_ms = 0;
  std::optional<std::int64_t> started_ms;
  std::optional<std::int64_t> finished_ms;
  std::string error_json;   // problem JSON when failed
  std::string result_json;  // result manifest JSON when succeeded
  std::string body_sha256;
};

struct NewJob {
  std::string id;
  std::string name;
  proto::JobKind kind = proto::JobKind::kImage;
  std::string spec_json;    // canonical job JSON
  std::string body_sha256;  // fingerprint of the request body (idempotency)
  std::optional<std::string> idempotency_key;
  std::int64_t created_ms = 0;
};

enum class CancelOutcome { kNotFound, kCanceled, kRequested, kAlreadyFinal };

// What recover() did with the jobs a previous process left running.
struct Recovery {
  std::vector<std::string> queued;  // every queued job, oldest first (re-queued ones included)
  int requeued = 0;
  int canceled = 0;
  int failed = 0;  // ran out of attempts
};

class JobStore {
 public:
  explicit JobStore(const std::filesystem::path& file);

  // Inserts the job; when its idempotency key exists already, inserts nothing and returns that job's row.
  // Returns nullopt when inserted.
  std::optional<JobRow> insert(const NewJob& job);
  std::optional<JobRow> find_by_idempotency_key(const std::string& key);

  std::optional<JobRow> get(const std::string& id);
  std::optional<std::string> spec_json(const std::string& id);
  // Newest first; rows with seq < before_seq when given; state filter when given.
  std::vector<JobRow> list(std::optional<std::int64_t> before_seq, int limit, std::optional<proto::JobState> state);

  // queued → running, attempts + 1. False when the job is not queued (canceled meanwhile).
  bool mark_running(const std::string& id, std::int64_t now);
  // running → succeeded | failed | canceled with the result manifest or the error.
  void mark_finished(const std::string& id, proto::JobState state, std::int64_t now, int progress,
                     const std::string& error_json, const std::string& result_json);
  // running → queued for a graceful shutdown (the attempt is given back).
  void requeue(const std::string& id);
  CancelOutcome request_cancel(const std::string& id, std::int64_t now);

  // After a restart: running jobs with a cancel request → canceled; those already started `max_attempts` times →
  // failed; the others → queued. Returns all queued jobs in order.
  Recovery recover(int max_attempts, std::int64_t now);

  // Deletes finished jobs finished before `cutoff_ms`; returns their ids (their files are the caller's).
  std::vector<std::string> delete_finished_before(std::int64_t cutoff_ms);

  std::int64_t count(proto::JobState state);
  // "ok" when a read works and so does a write (tried again, at most every 2 s, when the last one
  // failed), else "failing: <why>".
  std::string health();
  bool healthy() { return health() == "ok"; }

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
  void note_write(const std::string& error);
  std::string write_error();

  std::mutex write_mutex_;
  SqliteConnection writer_;
  std::mutex read_mutex_;
  SqliteConnection reader_;
  std::mutex health_mutex_;
  std::string write_error_;                                   // what the last write threw; empty when it succeeded
  std::chrono::steady_clock::time_point last_write_probe_{};  // health()'s last trial write (under health_mutex_)
};

}  // namespace texwarp::server
