// SQLite job store: see job_store.hpp.
#include "texwarp/server/job_store.hpp"

#include <sqlite3.h>

#include <stdexcept>

#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/server/problem_types.hpp"

namespace texwarp::server {
namespace {

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  seq INTEGER PRIMARY KEY AUTOINCREMENT,
  id TEXT NOT NULL UNIQUE,
  name TEXT NOT NULL DEFAULT '',
  kind TEXT NOT NULL,
  state TEXT NOT NULL,
  progress INTEGER NOT NULL DEFAULT 0,
  attempts INTEGER NOT NULL DEFAULT 0,
  cancel_requested INTEGER NOT NULL DEFAULT 0,
  created_ms INTEGER NOT NULL,
  started_ms INTEGER,
  finished_ms INTEGER,
  spec TEXT NOT NULL,
  body_sha256 TEXT NOT NULL,
  idempotency_key TEXT UNIQUE,
  error TEXT NOT NULL DEFAULT '',
  result TEXT NOT NULL DEFAULT ''
);
CREATE INDEX IF NOT EXISTS jobs_by_state ON jobs(state, seq);
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
INSERT OR IGNORE INTO meta(key, value) VALUES ('schema_version', '1');
)sql";

constexpr const char* kColumns =
    "seq, id, name, kind, state, progress, attempts, cancel_requested, created_ms, started_ms, finished_ms, error, "
    "result, body_sha256";

JobRow read_row(const SqliteStatement& s) {
  JobRow r;
  r.seq = s.integer(0);
  r.id = s.text(1);
  r.name = s.text(2);
  r.kind = proto::parse_enum<proto::JobKind>(s.text(3), proto::InputLocation::file("jobs.kind"));
  r.state = proto::parse_enum<proto::JobState>(s.text(4), proto::InputLocation::file("jobs.state"));
  r.progress = static_cast<int>(s.integer(5));
  r.attempts = static_cast<int>(s.integer(6));
  r.cancel_requested = s.integer(7) != 0;
  r.created_ms = s.integer(8);
  if (!s.is_null(9)) r.started_ms = s.integer(9);
  if (!s.is_null(10)) r.finished_ms = s.integer(10);
  r.error_json = s.text(11);
  r.result_json = s.text(12);
  r.body_sha256 = s.text(13);
  return r;
}

void configure(SqliteConnection& db) {
  db.exec("PRAGMA journal_mode=WAL");
  db.exec("PRAGMA synchronous=FULL");
  db.exec("PRAGMA foreign_keys=ON");
}

}  // namespace

JobStore::JobStore(const std::filesystem::path& file) : writer_(file), reader_(file) {
  configure(writer_);
  writer_.exec(kSchema);
  configure(reader_);
}

std::optional<JobRow> JobStore::insert(const NewJob& job) {
  return write([&]() -> std::optional<JobRow> {
    SqliteTransaction tx(writer_);
    if (job.idempotency_key) {
      auto q = writer_.prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE idempotency_key = ?1");
      q.bind(1, *job.idempotency_key);
      if (q.step()) return read_row(q);
    }
    auto s = writer_.prepare("INSERT INTO jobs(id, name, kind, state, created_ms, spec, body_sha256, idempotency_key) "
                             "VALUES (?1, ?2, ?3, 'queued', ?4, ?5, ?6, ?7)");
    s.bind(1, job.id).bind(2, job.name).bind(3, proto::to_string(job.kind)).bind(4, job.created_ms);
    s.bind(5, job.spec_json).bind(6, job.body_sha256).bind_optional(7, job.idempotency_key);
    s.step();
    tx.commit();
    return std::nullopt;
  });
}

std::optional<JobRow> JobStore::find_by_idempotency_key(const std::string& key) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE idempotency_key = ?1");
  q.bind(1, key);
  if (q.step()) return read_row(q);
  return std::nullopt;
}

std::optional<JobRow> JobStore::get(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE id = ?1");
  q.bind(1, id);
  if (q.step()) return read_row(q);
  return std::nullopt;
}

std::optional<std::string> JobStore::spec_json(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare("SELECT spec FROM jobs WHERE id = ?1");
  q.bind(1, id);
  if (q.step()) return q.text(0);
  return std::nullopt;
}

std::vector<JobRow> JobStore::list(std::optional<std::int64_t> before_seq, int limit,
                                   std::optional<proto::JobState> state) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare(std::string("SELECT ") + kColumns +
                           " FROM jobs WHERE seq < ?1 AND (?2 IS NULL OR state = ?2) ORDER BY seq DESC LIMIT ?3");
  q.bind(1, before_seq.value_or(INT64_MAX));
  if (state) {
    q.bind(2, proto::to_string(*state));
  } else {
    q.bind_null(2);
  }
  q.bind(3, static_cast<std::int64_t>(limit));
  std::vector<JobRow> rows;
  while (q.step()) rows.push_back(read_row(q));
  return rows;
}

bool JobStore::mark_running(const std::string& id, std::int64_t now) {
  return write([&] {
    auto s =
        writer_.prepare("UPDATE jobs SET state = 'running', attempts = attempts + 1, started_ms = ?2, progress = 0 "
                        "WHERE id = ?1 AND state = 'queued'");
    s.bind(1, id).bind(2, now);
    s.step();
    return s.changes() == 1;
  });
}

void JobStore::mark_finished(const std::string& id, proto::JobState state, std::int64_t now, int progress,
                             const std::string& error_json, const std::string& result_json) {
  return write([&] {
    auto s = writer_.prepare(
        "UPDATE jobs SET state = ?2, finished_ms = ?3, progress = ?4, error = ?5, result = ?6 WHERE id = ?1");
    s.bind(1, id).bind(2, proto::to_string(state)).bind(3, now).bind(4, static_cast<std::int64_t>(progress));
    s.bind(5, error_json).bind(6, result_json);
    s.step();
  });
}

void JobStore::requeue(const std::string& id) {
  return write([&] {
    auto s = writer_.prepare(
        "UPDATE jobs SET state = 'queued', attempts = MAX(attempts - 1, 0), started_ms = NULL, progress = 0 "
        "WHERE id = ?1 AND state = 'running'");
    s.bind(1, id);
    s.step();
  });
}

CancelOutcome JobStore::request_cancel(const std::string& id, std::int64_t now) {
  return write([&] {
    SqliteTransaction tx(writer_);
    auto q = writer_.prepare("SELECT state FROM jobs WHERE id = ?1");
    q.bind(1, id);
    if (!q.step()) return CancelOutcome::kNotFound;
    const proto::JobState state =
        proto::parse_enum<proto::JobState>(q.text(0), proto::InputLocation::file("jobs.state"));
    CancelOutcome outcome = CancelOutcome::kAlreadyFinal;
    if (state == proto::JobState::kQueued) {
      auto s =
          writer_.prepare("UPDATE jobs SET state = 'canceled', cancel_requested = 1, finished_ms = ?2 WHERE id = ?1");
      s.bind(1, id).bind(2, now);
      s.step();
      outcome = CancelOutcome::kCanceled;
    } else if (state == proto::JobState::kRunning) {
      auto s = writer_.prepare("UPDATE jobs SET cancel_requested = 1 WHERE id = ?1");
      s.bind(1, id);
      s.step();
      outcome = CancelOutcome::kRequested;
    }
    tx.commit();
    return outcome;
  });
}

Recovery JobStore::recover(int max_attempts, std::int64_t now) {
  return write([&] {
    SqliteTransaction tx(writer_);
    Recovery r;
    {
      auto s = writer_.prepare(
          "UPDATE jobs SET state = 'canceled', finished_ms = ?1 WHERE state = 'running' AND cancel_requested = 1");
      s.bind(1, now);
      s.step();
      r.canceled = s.changes();
    }
    {
      const std::string error =
          proto::encode_problem(
              job_problem(ErrorKind::kAttemptsExhausted,
                          "the job was running when the server stopped " + std::to_string(max_attempts) +
                              " times; it is not run again (resubmit it if this was not the job's fault)"))
              .dump();
      auto s = writer_.prepare(
          "UPDATE jobs SET state = 'failed', finished_ms = ?1, error = ?2 WHERE state = 'running' AND attempts >= ?3");
      s.bind(1, now).bind(2, error).bind(3, static_cast<std::int64_t>(max_attempts));
      s.step();
      r.failed = s.changes();
    }
    {
      auto s =
          writer_.prepare("UPDATE jobs SET state = 'queued', started_ms = NULL, progress = 0 WHERE state = 'running'");
      s.step();
      r.requeued = s.changes();
    }
    auto q = writer_.prepare("SELECT id FROM jobs WHERE state = 'queued' ORDER BY seq");
    while (q.step()) r.queued.push_back(q.text(0));
    tx.commit();
    return r;
  });
}

std::vector<std::string> JobStore::delete_finished_before(std::int64_t cutoff_ms) {
  return write([&] {
    SqliteTransaction tx(writer_);
    std::vector<std::string> ids;
    auto q =
        writer_.prepare("SELECT id FROM jobs WHERE state IN ('succeeded', 'failed', 'canceled') AND finished_ms < ?1");
    q.bind(1, cutoff_ms);
    while (q.step()) ids.push_back(q.text(0));
    auto d =
        writer_.prepare("DELETE FROM jobs WHERE state IN ('succeeded', 'failed', 'canceled') AND finished_ms < ?1");
    d.bind(1, cutoff_ms);
    d.step();
    tx.commit();
    return ids;
  });
}

std::int64_t JobStore::count(proto::JobState state) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare("SELECT COUNT(*) FROM jobs WHERE state = ?1");
  q.bind(1, proto::to_string(state));
  q.step();
  return q.integer(0);
}

namespace {
constexpr auto kWriteProbeInterval = std::chrono::seconds(2);
}  // namespace

std::string JobStore::health() {
  try {
    std::lock_guard lock(read_mutex_);
    auto q = reader_.prepare("SELECT COUNT(*) FROM meta");
    if (!q.step()) return "failing: the store's meta table is empty";
  } catch (const std::exception& e) {
    return std::string("failing: ") + e.what();
  }
  if (write_error().empty()) return "ok";
  // The last write failed (a full disk, an I/O error): a write that changes nothing says whether it still does.
  // The log is checkpointed and cut first, or the write could fit in space the failed one left at its end. Probes
  // come often and this holds the write lock: tried at most every few seconds.
  {
    std::lock_guard lock(health_mutex_);
    const auto now = std::chrono::steady_clock::now();
    if (now - last_write_probe_ < kWriteProbeInterval) return "failing: " + write_error_;
    last_write_probe_ = now;
  }
  try {
    write([&] {
      writer_.exec("PRAGMA wal_checkpoint(TRUNCATE)");
      writer_.exec("UPDATE meta SET value = value WHERE key = 'schema_version'");
    });
  } catch (const std::exception&) {
  }
  const std::string error = write_error();
  return error.empty() ? "ok" : "failing: " + error;
}

void JobStore::note_write(const std::string& error) {
  std::lock_guard lock(health_mutex_);
  write_error_ = error;
}

std::string JobStore::write_error() {
  std::lock_guard lock(health_mutex_);
  return write_error_;
}

}  // namespace texwarp::server
