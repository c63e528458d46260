// SQLite job store: see sqlite_job_store.hpp. Schema 1 is the first release's; schema 2 adds priority, labels, the
// lease (node, epoch, expiry), the result folder and the node registry. A new file is made at 1 and migrated.
#include "texwarp/server/sqlite_job_store.hpp"

#include <sqlite3.h>

#include <climits>
#include <stdexcept>

#include "job_store_rows.hpp"
#include "texwarp/proto/enum_names.hpp"

namespace texwarp::server {
namespace {

// The first release's schema, exactly as it made new files (a new file starts here and is migrated).
constexpr const char* kSchema1 = R"sql(
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

// 1 → 2. Rows that succeeded before keep their files where the first release put them: results/<id>/.
constexpr const char* kMigration2 = R"sql(
ALTER TABLE jobs ADD COLUMN priority INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN labels TEXT NOT NULL DEFAULT '{}';
ALTER TABLE jobs ADD COLUMN node_id TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN lease_epoch INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN lease_expires_ms INTEGER;
ALTER TABLE jobs ADD COLUMN result_folder TEXT NOT NULL DEFAULT '';
UPDATE jobs SET result_folder = id WHERE state = 'succeeded';
CREATE INDEX jobs_claim ON jobs(priority DESC, seq) WHERE state = 'queued';
CREATE INDEX jobs_by_finished ON jobs(finished_ms) WHERE finished_ms IS NOT NULL;
CREATE TABLE nodes (
  id TEXT PRIMARY KEY,
  address TEXT NOT NULL,
  version TEXT NOT NULL,
  workers INTEGER NOT NULL,
  pid INTEGER NOT NULL,
  started_ms INTEGER NOT NULL,
  last_seen_ms INTEGER NOT NULL,
  running INTEGER NOT NULL DEFAULT 0
);
UPDATE meta SET value = '2' WHERE key = 'schema_version';
)sql";

constexpr const char* kColumns =
    "seq, id, name, kind, state, priority, labels, progress, attempts, cancel_requested, created_ms, started_ms, "
    "finished_ms, error, result, result_folder, body_sha256, node_id, lease_epoch, lease_expires_ms";

constexpr const char* kFinished = "state IN ('succeeded', 'failed', 'canceled')";

std::optional<std::int64_t> optional_integer(const SqliteStatement& s, int column) {
  if (s.is_null(column)) return std::nullopt;
  return s.integer(column);
}

JobRow read_row(const SqliteStatement& s) {
  JobRow r;
  r.seq = s.integer(0);
  r.id = s.text(1);
  r.name = s.text(2);
  r.kind = store_rows::decode_kind(s.text(3), "jobs.kind of job " + r.id);
  r.state = store_rows::decode_state(s.text(4), "jobs.state of job " + r.id);
  r.priority = static_cast<int>(s.integer(5));
  r.labels = store_rows::decode_labels(s.text(6), "jobs.labels of job " + r.id);
  r.progress = static_cast<int>(s.integer(7));
  r.attempts = static_cast<int>(s.integer(8));
  r.cancel_requested = s.integer(9) != 0;
  r.created_ms = s.integer(10);
  r.started_ms = optional_integer(s, 11);
  r.finished_ms = optional_integer(s, 12);
  r.error_json = s.text(13);
  r.result_json = s.text(14);
  r.result_folder = s.text(15);
  r.body_sha256 = s.text(16);
  r.node_id = s.text(17);
  r.lease_epoch = s.integer(18);
  r.lease_expires_ms = optional_integer(s, 19);
  return r;
}

void configure(SqliteConnection& db) {
  db.exec("PRAGMA journal_mode=WAL");
  db.exec("PRAGMA synchronous=FULL");
  db.exec("PRAGMA foreign_keys=ON");
}

bool has_table(SqliteConnection& db, const char* name) {
  auto q = db.prepare("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?1");
  q.bind(1, name);
  return q.step();
}

// The file's schema version: 0 when it holds no tables at all (a new file).
int stored_version(SqliteConnection& db, const std::filesystem::path& file) {
  if (!has_table(db, "meta")) {
    if (has_table(db, "jobs")) throw std::runtime_error(file.string() + " has a jobs table but no schema version");
    return 0;
  }
  auto q = db.prepare("SELECT value FROM meta WHERE key = 'schema_version'");
  if (!q.step()) throw std::runtime_error(file.string() + ": meta.schema_version is missing");
  const std::string text = q.text(0);
  try {
    std::size_t used = 0;
    const int version = std::stoi(text, &used);
    if (used == text.size() && version >= 1) return version;
  } catch (const std::exception&) {
  }
  throw std::runtime_error(file.string() + ": meta.schema_version is \"" + text.substr(0, 40) + "\", not a version");
}

void migrate(SqliteConnection& db, const std::filesystem::path& file) {
  SqliteTransaction tx(db);  // BEGIN IMMEDIATE: two processes opening the file at once migrate it once
  int version = stored_version(db, file);
  if (version > JobStore::kSchemaVersion) {
    throw std::runtime_error(file.string() + " has job store schema version " + std::to_string(version) +
                             ", newer than this texwarpd's " + std::to_string(JobStore::kSchemaVersion) +
                             " (run a newer texwarpd)");
  }
  if (version == 0) {
    db.exec(kSchema1);
    version = 1;
  }
  if (version == 1) db.exec(kMigration2);
  tx.commit();
}

}  // namespace

SqliteJobStore::SqliteJobStore(const std::filesystem::path& file) : file_(file), writer_(file), reader_(file) {
  try {
    configure(writer_);
    migrate(writer_, file);
    configure(reader_);
  } catch (const std::system_error&) {
    throw;  // a full disk stays a full disk
  } catch (const std::exception& e) {
    throw std::runtime_error("job store " + file.string() + ": " + e.what());
  }
}

int SqliteJobStore::schema_version() {
  std::lock_guard lock(read_mutex_);
  return stored_version(reader_, file_);
}

Inserted SqliteJobStore::insert_locked(const NewJob& job) {
  if (job.idempotency_key) {
    auto q = writer_.prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE idempotency_key = ?1");
    q.bind(1, *job.idempotency_key);
    if (q.step()) return {read_row(q), true};
  }
  auto s = writer_.prepare(
      std::string("INSERT INTO jobs(id, name, kind, state, priority, labels, created_ms, spec, body_sha256, "
                  "idempotency_key) VALUES (?1, ?2, ?3, 'queued', ?4, ?5, ?6, ?7, ?8, ?9) RETURNING ") +
      kColumns);
  s.bind(1, job.id).bind(2, job.name).bind(3, proto::to_string(job.kind)).bind(4, std::int64_t{job.priority});
  s.bind(5, store_rows::encode_labels(job.labels)).bind(6, job.created_ms).bind(7, job.spec_json);
  s.bind(8, job.body_sha256).bind_optional(9, job.idempotency_key);
  if (!s.step())
    throw std::runtime_error("job store " + file_.string() + ": the insert of job " + job.id + " said nothing");
  Inserted inserted{read_row(s), false};
  s.step();  // to the statement's end (SQLite reports a failed write there)
  return inserted;
}

Inserted SqliteJobStore::insert(const NewJob& job) {
  return write([&] {
    SqliteTransaction tx(writer_);
    Inserted inserted = insert_locked(job);
    tx.commit();
    return inserted;
  });
}

std::vector<Inserted> SqliteJobStore::insert_batch(const std::vector<NewJob>& jobs) {
  return write([&] {
    SqliteTransaction tx(writer_);
    std::vector<Inserted> answers;
    answers.reserve(jobs.size());
    for (const auto& job : jobs) answers.push_back(insert_locked(job));
    tx.commit();
    return answers;
  });
}

std::optional<JobRow> SqliteJobStore::get(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE id = ?1");
  q.bind(1, id);
  if (q.step()) return read_row(q);
  return std::nullopt;
}

std::optional<JobRow> SqliteJobStore::find_by_idempotency_key(const std::string& key) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare(std::string("SELECT ") + kColumns + " FROM jobs WHERE idempotency_key = ?1");
  q.bind(1, key);
  if (q.step()) return read_row(q);
  return std::nullopt;
}

std::optional<std::string> SqliteJobStore::spec_json(const std::string& id) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare("SELECT spec FROM jobs WHERE id = ?1");
  q.bind(1, id);
  if (q.step()) return q.text(0);
  return std::nullopt;
}

std::vector<JobRow> SqliteJobStore::list(const ListQuery& query) {
  if (query.limit <= 0) return {};
  std::string sql = std::string("SELECT ") + kColumns + " FROM jobs WHERE seq < ?1 AND (?2 IS NULL OR state = ?2)";
  int index = 4;
  for (std::size_t i = 0; i < query.labels.size(); ++i, index += 2) {
    sql += " AND EXISTS (SELECT 1 FROM json_each(jobs.labels) WHERE key = ?" + std::to_string(index) +
           " AND type = 'text' AND value = ?" + std::to_string(index + 1) + ")";
  }
  sql += " ORDER BY seq DESC LIMIT ?3";
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare(sql);
  q.bind(1, query.before_seq.value_or(INT64_MAX));
  if (query.state) {
    q.bind(2, proto::to_string(*query.state));
  } else {
    q.bind_null(2);
  }
  q.bind(3, std::int64_t{query.limit});
  index = 4;
  for (const auto& [key, value] : query.labels) {
    q.bind(index++, key);
    q.bind(index++, value);
  }
  std::vector<JobRow> rows;
  while (q.step()) rows.push_back(read_row(q));
  return rows;
}

std::optional<Lease> SqliteJobStore::claim(const std::string& node_id, std::int64_t now_ms, std::int64_t lease_ms) {
  return write([&]() -> std::optional<Lease> {
    // One statement, so one short write transaction. The sub-select walks the partial index jobs_claim (named: the
    // planner, without statistics, would rather take jobs_by_state and sort every queued row).
    auto s = writer_.prepare(
        "UPDATE jobs SET state = 'running', node_id = ?1, attempts = attempts + 1, lease_epoch = lease_epoch + 1, "
        "started_ms = ?2, lease_expires_ms = ?3, progress = 0 "
        "WHERE seq = (SELECT seq FROM jobs INDEXED BY jobs_claim WHERE state = 'queued' "
        "ORDER BY priority DESC, seq LIMIT 1) "
        "AND state = 'queued' RETURNING id, lease_epoch, attempts, spec");
    s.bind(1, node_id).bind(2, now_ms).bind(3, now_ms + lease_ms);
    if (!s.step()) return std::nullopt;
    Lease lease{s.text(0), s.integer(1), static_cast<int>(s.integer(2)), s.text(3)};
    s.step();
    return lease;
  });
}

Renewal SqliteJobStore::renew(const std::string& id, std::int64_t epoch, int progress, std::int64_t now_ms,
                              std::int64_t lease_ms) {
  return write([&] {
    auto s = writer_.prepare(
        "UPDATE jobs SET lease_expires_ms = ?3, progress = ?4 WHERE id = ?1 AND lease_epoch = ?2 AND state = "
        "'running' RETURNING cancel_requested");
    s.bind(1, id).bind(2, epoch).bind(3, now_ms + lease_ms).bind(4, std::int64_t{progress});
    Renewal renewal;
    if (s.step()) {
      renewal.held = true;
      renewal.cancel_requested = s.integer(0) != 0;
      s.step();
    }
    return renewal;
  });
}

bool SqliteJobStore::finish(const std::string& id, std::int64_t epoch, proto::JobState state, std::int64_t now_ms,
                            int progress, const std::string& error_json, const std::string& result_json,
                            const std::string& result_folder) {
  store_rows::require_final_state(state);
  return write([&] {
    auto s = writer_.prepare(
        "UPDATE jobs SET state = ?3, finished_ms = ?4, progress = ?5, error = ?6, result = ?7, result_folder = ?8, "
        "lease_expires_ms = NULL WHERE id = ?1 AND lease_epoch = ?2 AND state = 'running'");
    s.bind(1, id).bind(2, epoch).bind(3, proto::to_string(state)).bind(4, now_ms).bind(5, std::int64_t{progress});
    s.bind(6, error_json).bind(7, result_json).bind(8, result_folder);
    s.step();
    return s.changes() == 1;
  });
}

bool SqliteJobStore::release(const std::string& id, std::int64_t epoch) {
  return write([&] {
    auto s = writer_.prepare(
        "UPDATE jobs SET state = 'queued', attempts = MAX(attempts - 1, 0), started_ms = NULL, progress = 0, "
        "lease_expires_ms = NULL WHERE id = ?1 AND lease_epoch = ?2 AND state = 'running'");
    s.bind(1, id).bind(2, epoch);
    s.step();
    return s.changes() == 1;
  });
}

CancelOutcome SqliteJobStore::request_cancel(const std::string& id, std::int64_t now_ms) {
  return write([&] {
    SqliteTransaction tx(writer_);
    auto q = writer_.prepare("SELECT state FROM jobs WHERE id = ?1");
    q.bind(1, id);
    if (!q.step()) return CancelOutcome::kNotFound;
    const proto::JobState state = store_rows::decode_state(q.text(0), "jobs.state of job " + id);
    CancelOutcome outcome = CancelOutcome::kAlreadyFinal;
    if (state == proto::JobState::kQueued) {
      auto s =
          writer_.prepare("UPDATE jobs SET state = 'canceled', cancel_requested = 1, finished_ms = ?2 WHERE id = ?1");
      s.bind(1, id).bind(2, now_ms);
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

Reclaimed SqliteJobStore::reclaim_expired(std::int64_t now_ms, int max_attempts,
                                          const std::optional<std::string>& node_id) {
  // ?1: now; ?2: the node whose leases are all dead (NULL: every lease that expired before now). A lease without
  // an expiry (a row from schema 1) has expired.
  const std::string dead =
      "state = 'running' AND (CASE WHEN ?2 IS NULL THEN lease_expires_ms IS NULL OR lease_expires_ms < ?1 "
      "ELSE node_id = ?2 END)";
  return write([&] {
    SqliteTransaction tx(writer_);
    Reclaimed r;
    const auto bind_dead = [&](SqliteStatement& s) {
      s.bind(1, now_ms);
      if (node_id) {
        s.bind(2, *node_id);
      } else {
        s.bind_null(2);
      }
    };
    {
      auto s = writer_.prepare("UPDATE jobs SET state = 'canceled', finished_ms = ?1, lease_expires_ms = NULL WHERE " +
                               dead + " AND cancel_requested = 1");
      bind_dead(s);
      s.step();
      r.canceled = s.changes();
    }
    {
      auto s = writer_.prepare(
          "UPDATE jobs SET state = 'failed', finished_ms = ?1, error = ?3, lease_expires_ms = NULL WHERE " + dead +
          " AND attempts >= ?4");
      bind_dead(s);
      s.bind(3, store_rows::attempts_exhausted_error(max_attempts)).bind(4, std::int64_t{max_attempts});
      s.step();
      r.failed = s.changes();
    }
    {
      auto q = writer_.prepare("SELECT id FROM jobs WHERE " + dead + " ORDER BY seq");
      bind_dead(q);
      while (q.step()) r.requeued.push_back(q.text(0));
      auto s = writer_.prepare(
          "UPDATE jobs SET state = 'queued', started_ms = NULL, progress = 0, lease_expires_ms = NULL WHERE " + dead);
      bind_dead(s);
      s.step();
    }
    tx.commit();
    return r;
  });
}

PurgeOutcome SqliteJobStore::purge(const std::string& id) {
  return write([&] {
    SqliteTransaction tx(writer_);
    auto q = writer_.prepare("SELECT state FROM jobs WHERE id = ?1");
    q.bind(1, id);
    if (!q.step()) return PurgeOutcome::kNotFound;
    if (!proto::is_terminal(store_rows::decode_state(q.text(0), "jobs.state of job " + id))) {
      return PurgeOutcome::kNotFinished;
    }
    auto d = writer_.prepare(std::string("DELETE FROM jobs WHERE id = ?1 AND ") + kFinished);
    d.bind(1, id);
    d.step();
    tx.commit();
    return PurgeOutcome::kPurged;
  });
}

std::vector<std::string> SqliteJobStore::delete_finished_before(std::int64_t cutoff_ms) {
  return write([&] {
    SqliteTransaction tx(writer_);
    std::vector<std::string> ids;
    auto q = writer_.prepare(std::string("SELECT id FROM jobs WHERE ") + kFinished + " AND finished_ms < ?1");
    q.bind(1, cutoff_ms);
    while (q.step()) ids.push_back(q.text(0));
    auto d = writer_.prepare(std::string("DELETE FROM jobs WHERE ") + kFinished + " AND finished_ms < ?1");
    d.bind(1, cutoff_ms);
    d.step();
    tx.commit();
    return ids;
  });
}

std::int64_t SqliteJobStore::count(proto::JobState state) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare("SELECT COUNT(*) FROM jobs WHERE state = ?1");
  q.bind(1, proto::to_string(state));
  q.step();
  return q.integer(0);
}

FinishedSince SqliteJobStore::finished_since(std::int64_t since_ms) {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare(std::string("SELECT COUNT(*), MIN(finished_ms) FROM jobs WHERE finished_ms >= ?1 AND ") +
                           kFinished);
  q.bind(1, since_ms);
  q.step();
  FinishedSince out;
  out.count = q.integer(0);
  if (out.count > 0) out.oldest_ms = q.integer(1);
  return out;
}

void SqliteJobStore::register_node(const NodeInfo& node) {
  write([&] {
    auto s = writer_.prepare(
        "INSERT INTO nodes(id, address, version, workers, pid, started_ms, last_seen_ms, running) "
        "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8) ON CONFLICT(id) DO UPDATE SET address = excluded.address, "
        "version = excluded.version, workers = excluded.workers, pid = excluded.pid, started_ms = excluded.started_ms, "
        "last_seen_ms = excluded.last_seen_ms, running = excluded.running");
    s.bind(1, node.id).bind(2, node.address).bind(3, node.version).bind(4, std::int64_t{node.workers});
    s.bind(5, node.pid).bind(6, node.started_ms).bind(7, node.last_seen_ms).bind(8, std::int64_t{node.running});
    s.step();
  });
}

void SqliteJobStore::heartbeat_node(const std::string& node_id, std::int64_t now_ms, int running) {
  write([&] {
    auto s = writer_.prepare("UPDATE nodes SET last_seen_ms = ?2, running = ?3 WHERE id = ?1");
    s.bind(1, node_id).bind(2, now_ms).bind(3, std::int64_t{running});
    s.step();
  });
}

void SqliteJobStore::remove_node(const std::string& node_id) {
  write([&] {
    auto s = writer_.prepare("DELETE FROM nodes WHERE id = ?1");
    s.bind(1, node_id);
    s.step();
  });
}

std::vector<NodeInfo> SqliteJobStore::nodes() {
  std::lock_guard lock(read_mutex_);
  auto q = reader_.prepare(
      "SELECT id, address, version, workers, pid, started_ms, last_seen_ms, running FROM nodes ORDER BY id");
  std::vector<NodeInfo> nodes;
  while (q.step()) {
    nodes.push_back({q.text(0), q.text(1), q.text(2), static_cast<int>(q.integer(3)), q.integer(4), q.integer(5),
                     q.integer(6), static_cast<int>(q.integer(7))});
  }
  return nodes;
}

namespace {
// SQLite's single node always holds it (its data folder is locked to one process).
class SingleNodeMaintenanceLock final : public MaintenanceLock {};
}  // namespace

std::unique_ptr<MaintenanceLock> SqliteJobStore::try_maintenance_lock() {
  return std::make_unique<SingleNodeMaintenanceLock>();
}

namespace {
constexpr auto kWriteProbeInterval = std::chrono::seconds(2);
}  // namespace

std::string SqliteJobStore::health() {
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

void SqliteJobStore::note_write(const std::string& error) {
  std::lock_guard lock(health_mutex_);
  write_error_ = error;
}

std::string SqliteJobStore::write_error() {
  std::lock_guard lock(health_mutex_);
  return write_error_;
}

}  // namespace texwarp::server
