// PostgreSQL job store: see postgres_job_store.hpp. The schema's versions are the SQLite store's: 1 is the first
// release's job table, 2 adds priority, labels (jsonb), the lease (node, epoch, expiry), the result folder and the
// node registry.
#include "texwarp/server/postgres_job_store.hpp"

#include <pqxx/pqxx>

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string_view>
#include <utility>
#include <vector>

#include "job_store_rows.hpp"
#include "texwarp/proto/enum_names.hpp"

namespace texwarp::server {

struct PgConnection {
  explicit PgConnection(const std::string& url) : c(url) {}
  pqxx::connection c;
};

namespace {

// Advisory lock keys ("texwarp" and a digit, as 8 bytes).
constexpr std::int64_t kMigrationLockKey = 0x7465787761727031;
constexpr std::int64_t kMaintenanceLockKey = 0x7465787761727032;

// kMigrations[v - 1] takes the schema from version v - 1 to v.
constexpr std::array<const char*, JobStore::kSchemaVersion> kMigrations = {
    R"sql(
CREATE TABLE jobs (
  seq BIGSERIAL PRIMARY KEY,
  id TEXT NOT NULL UNIQUE,
  name TEXT NOT NULL DEFAULT '',
  kind TEXT NOT NULL,
  state TEXT NOT NULL,
  progress INTEGER NOT NULL DEFAULT 0,
  attempts INTEGER NOT NULL DEFAULT 0,
  cancel_requested BOOLEAN NOT NULL DEFAULT false,
  created_ms BIGINT NOT NULL,
  started_ms BIGINT,
  finished_ms BIGINT,
  spec TEXT NOT NULL,
  body_sha256 TEXT NOT NULL,
  idempotency_key TEXT UNIQUE,
  error TEXT NOT NULL DEFAULT '',
  result TEXT NOT NULL DEFAULT ''
);
CREATE INDEX jobs_by_state ON jobs(state, seq);
)sql",
    R"sql(
ALTER TABLE jobs
  ADD COLUMN priority INTEGER NOT NULL DEFAULT 0,
  ADD COLUMN labels JSONB NOT NULL DEFAULT '{}',
  ADD COLUMN node_id TEXT NOT NULL DEFAULT '',
  ADD COLUMN lease_epoch BIGINT NOT NULL DEFAULT 0,
  ADD COLUMN lease_expires_ms BIGINT,
  ADD COLUMN result_folder TEXT NOT NULL DEFAULT '';
UPDATE jobs SET result_folder = id WHERE state = 'succeeded';
CREATE INDEX jobs_claim ON jobs(priority DESC, seq) WHERE state = 'queued';
CREATE INDEX jobs_by_finished ON jobs(finished_ms) WHERE finished_ms IS NOT NULL;
CREATE INDEX jobs_by_labels ON jobs USING gin (labels jsonb_path_ops);
CREATE TABLE nodes (
  id TEXT PRIMARY KEY,
  address TEXT NOT NULL,
  version TEXT NOT NULL,
  workers INTEGER NOT NULL,
  pid BIGINT NOT NULL,
  started_ms BIGINT NOT NULL,
  last_seen_ms BIGINT NOT NULL,
  running INTEGER NOT NULL DEFAULT 0
);
)sql"};

constexpr const char* kColumns =
    "seq, id, name, kind, state, priority, labels::text, progress, attempts, cancel_requested, created_ms, "
    "started_ms, finished_ms, error, result, result_folder, body_sha256, node_id, lease_epoch, lease_expires_ms";

constexpr const char* kFinished = "state IN ('succeeded', 'failed', 'canceled')";

std::string cols(const std::string& sql) { return sql + kColumns; }

// The prepared statements of every connection, by name.
const std::vector<std::pair<std::string, std::string>>& statements() {
  static const std::vector<std::pair<std::string, std::string>> kAll = {
      {"insert", cols("INSERT INTO jobs(id, name, kind, state, priority, labels, created_ms, spec, body_sha256, "
                      "idempotency_key) VALUES ($1, $2, $3, 'queued', $4, $5::jsonb, $6, $7, $8, $9) "
                      "ON CONFLICT (idempotency_key) DO NOTHING RETURNING ")},
      {"by_key", cols("SELECT ") + " FROM jobs WHERE idempotency_key = $1"},
      {"get", cols("SELECT ") + " FROM jobs WHERE id = $1"},
      {"spec", "SELECT spec FROM jobs WHERE id = $1"},
      {"list", cols("SELECT ") + " FROM jobs WHERE seq < $1 AND ($2 = '' OR state = $2) ORDER BY seq DESC LIMIT $3"},
      {"list_labeled", cols("SELECT ") +
                           " FROM jobs WHERE seq < $1 AND ($2 = '' OR state = $2) AND labels @> $4::jsonb "
                           "ORDER BY seq DESC LIMIT $3"},
      {"claim",
       "UPDATE jobs SET state = 'running', node_id = $1, attempts = attempts + 1, lease_epoch = lease_epoch + 1, "
       "started_ms = $2, lease_expires_ms = $2::bigint + $3::bigint, progress = 0 "
       "WHERE seq = (SELECT seq FROM jobs WHERE state = 'queued' ORDER BY priority DESC, seq LIMIT 1 "
       "FOR UPDATE SKIP LOCKED) RETURNING id, lease_epoch, attempts, spec"},
      {"renew",
       "UPDATE jobs SET lease_expires_ms = $3, progress = $4 WHERE id = $1 AND lease_epoch = $2 AND state = 'running' "
       "RETURNING cancel_requested"},
      {"finish",
       "UPDATE jobs SET state = $3, finished_ms = $4, progress = $5, error = $6, result = $7, result_folder = $8, "
       "lease_expires_ms = NULL WHERE id = $1 AND lease_epoch = $2 AND state = 'running'"},
      {"release",
       "UPDATE jobs SET state = 'queued', attempts = GREATEST(attempts - 1, 0), started_ms = NULL, progress = 0, "
       "lease_expires_ms = NULL WHERE id = $1 AND lease_epoch = $2 AND state = 'running'"},
      {"count", "SELECT COUNT(*) FROM jobs WHERE state = $1"},
      {"finished_since",
       std::string("SELECT COUNT(*), MIN(finished_ms) FROM jobs WHERE finished_ms >= $1 AND ") + kFinished},
      {"heartbeat", "UPDATE nodes SET last_seen_ms = $2, running = $3 WHERE id = $1"},
  };
  return kAll;
}

std::optional<std::int64_t> optional_integer(const pqxx::field& f) {
  if (f.is_null()) return std::nullopt;
  return f.as<std::int64_t>();
}

JobRow read_row(const pqxx::row& r) {
  JobRow row;
  row.seq = r[0].as<std::int64_t>();
  row.id = r[1].as<std::string>();
  row.name = r[2].as<std::string>();
  row.kind = store_rows::decode_kind(r[3].as<std::string>(), "jobs.kind of job " + row.id);
  row.state = store_rows::decode_state(r[4].as<std::string>(), "jobs.state of job " + row.id);
  row.priority = r[5].as<int>();
  row.labels = store_rows::decode_labels(r[6].as<std::string>(), "jobs.labels of job " + row.id);
  row.progress = r[7].as<int>();
  row.attempts = r[8].as<int>();
  row.cancel_requested = r[9].as<bool>();
  row.created_ms = r[10].as<std::int64_t>();
  row.started_ms = optional_integer(r[11]);
  row.finished_ms = optional_integer(r[12]);
  row.error_json = r[13].as<std::string>();
  row.result_json = r[14].as<std::string>();
  row.result_folder = r[15].as<std::string>();
  row.body_sha256 = r[16].as<std::string>();
  row.node_id = r[17].as<std::string>();
  row.lease_epoch = r[18].as<std::int64_t>();
  row.lease_expires_ms = optional_integer(r[19]);
  return row;
}

// `text` with its %XX escapes decoded (libpq decodes a URI's parameter names and values so).
std::string percent_decoded(std::string_view text) {
  const auto hex = [](char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '%' && i + 2 < text.size() && hex(text[i + 1]) >= 0 && hex(text[i + 2]) >= 0) {
      out.push_back(static_cast<char>(hex(text[i + 1]) * 16 + hex(text[i + 2])));
      i += 2;
    } else {
      out.push_back(text[i]);
    }
  }
  return out;
}

// Whether a URI query parameter ("name=value") sets the password: its name is "password" once decoded.
bool is_password_parameter(std::string_view param) {
  return percent_decoded(param.substr(0, param.find('='))) == "password";
}

// The URL's passwords (in the user info, every password= parameter; each as written and decoded), for scrubbing.
std::vector<std::string> passwords_of(const std::string& url) {
  std::vector<std::string> out;
  const auto add = [&](const std::string& raw) {
    if (raw.empty()) return;
    out.push_back(raw);
    if (const std::string decoded = percent_decoded(raw); decoded != raw && !decoded.empty()) out.push_back(decoded);
  };
  const auto scheme = url.find("://");
  if (scheme == std::string::npos) return out;
  const std::size_t start = scheme + 3;
  const std::size_t query = url.find('?');
  const std::size_t end = std::min(url.find_first_of("/?", start), url.size());
  const std::size_t at = url.rfind('@', end == 0 ? 0 : end - 1);
  if (at != std::string::npos && at >= start) {
    const std::size_t colon = url.find(':', start);
    if (colon < at) add(url.substr(colon + 1, at - colon - 1));
  }
  for (std::size_t p = query == std::string::npos ? url.size() : query + 1; p < url.size();) {
    const std::size_t next = std::min(url.find('&', p), url.size());
    const std::string_view param = std::string_view(url).substr(p, next - p);
    if (is_password_parameter(param) && param.find('=') != std::string_view::npos) {
      add(std::string(param.substr(param.find('=') + 1)));
    }
    p = next + 1;
  }
  return out;
}

// `message` with every occurrence of the URL's password replaced (libpq may quote parts of a URL it cannot parse).
std::string scrubbed(std::string message, const std::string& url) {
  for (const std::string& password : passwords_of(url)) {
    for (std::size_t at = message.find(password); at != std::string::npos; at = message.find(password, at)) {
      message.replace(at, password.size(), "***");
    }
  }
  return message;
}

// The first line of a libpq message, scrubbed.
std::string why(const std::exception& e, const std::string& url) {
  std::string text = e.what();
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  const auto newline = text.find('\n');
  if (newline != std::string::npos) text = text.substr(0, newline);
  return scrubbed(text, url);
}

// The URL with the connection options a store needs when it does not set them: a bounded connect, TCP keepalives
// (a dead server is noticed), and a name in pg_stat_activity.
std::string with_options(const std::string& url) {
  std::string out = url;
  const auto add = [&](const std::string& key, const std::string& value) {
    if (url.find(key + "=") != std::string::npos) return;
    out += (out.find('?') == std::string::npos ? "?" : "&") + key + "=" + value;
  };
  add("connect_timeout", "10");
  add("keepalives_idle", "10");
  add("keepalives_interval", "5");
  add("keepalives_count", "3");
  add("application_name", "texwarpd");
  return out;
}

// Whether `e`, thrown while using `c`, means the connection is gone (the server stopped or restarted, the network
// broke, the backend was terminated).
bool connection_lost(const std::exception& e, pqxx::connection& c) {
  if (dynamic_cast<const pqxx::broken_connection*>(&e) != nullptr) return true;
  if (dynamic_cast<const pqxx::in_doubt_error*>(&e) != nullptr) return true;
  if (const auto* sql = dynamic_cast<const pqxx::sql_error*>(&e)) {
    const std::string state = sql->sqlstate();
    // 08: connection exception; 57P01–57P03: admin shutdown, crash shutdown, cannot connect now.
    if (state.rfind("08", 0) == 0 || state.rfind("57P", 0) == 0) return true;
  }
  return !c.is_open();
}

int stored_version(pqxx::transaction_base& tx) {
  if (tx.exec("SELECT to_regclass('texwarp_schema') IS NULL")[0][0].as<bool>()) return 0;
  return tx.exec("SELECT COALESCE(MAX(version), 0) FROM texwarp_schema")[0][0].as<int>();
}

std::string newer_schema(const std::string& redacted, int version) {
  return "job store " + redacted + " has schema version " + std::to_string(version) + ", newer than this texwarpd's " +
         std::to_string(JobStore::kSchemaVersion) + " (run a newer texwarpd)";
}

class PostgresMaintenanceLock final : public MaintenanceLock {
 public:
  explicit PostgresMaintenanceLock(std::unique_ptr<PgConnection> connection) : c_(std::move(connection)) {}
  ~PostgresMaintenanceLock() override {
    try {
      pqxx::nontransaction tx(c_->c);
      tx.exec_params("SELECT pg_advisory_unlock($1)", kMaintenanceLockKey);
    } catch (const std::exception&) {
      // The connection closes below: the server lets the lock go with it.
    }
  }

 private:
  std::unique_ptr<PgConnection> c_;
};

}  // namespace

// A connection borrowed from the pool for one call; back to the pool when done unless discarded.
class PostgresJobStore::Borrowed {
 public:
  explicit Borrowed(PostgresJobStore& store) : store_(store) {
    {
      std::unique_lock lock(store_.pool_mutex_);
      store_.pool_returned_.wait(lock,
                                 [&] { return !store_.idle_.empty() || store_.borrowed_ < store_.max_connections_; });
      ++store_.borrowed_;
      if (!store_.idle_.empty()) {
        c_ = std::move(store_.idle_.back());
        store_.idle_.pop_back();
      }
    }
    if (!c_) {
      try {
        c_ = store_.open_connection();
      } catch (...) {
        give_back();
        throw;
      }
    }
  }
  ~Borrowed() { give_back(); }
  Borrowed(const Borrowed&) = delete;
  Borrowed& operator=(const Borrowed&) = delete;

  pqxx::connection& connection() { return c_->c; }
  void discard() { c_.reset(); }

 private:
  void give_back() {
    std::lock_guard lock(store_.pool_mutex_);
    --store_.borrowed_;
    if (c_ && c_->c.is_open()) store_.idle_.push_back(std::move(c_));
    c_.reset();
    store_.pool_returned_.notify_one();
  }

  PostgresJobStore& store_;
  std::unique_ptr<PgConnection> c_;
};

template <class F>
auto PostgresJobStore::with_connection(bool write, F&& f) {
  const auto note = [&](const std::string& error) {
    if (!write) return;
    std::lock_guard lock(health_mutex_);
    write_error_ = error;
  };
  std::unique_ptr<Borrowed> borrowed;
  try {
    borrowed = std::make_unique<Borrowed>(*this);
  } catch (const std::exception& e) {
    note(e.what());
    throw;
  }
  try {
    if constexpr (std::is_void_v<std::invoke_result_t<F&, pqxx::connection&>>) {
      f(borrowed->connection());
      note({});
    } else {
      auto result = f(borrowed->connection());
      note({});
      return result;
    }
  } catch (const std::exception& e) {
    if (connection_lost(e, borrowed->connection())) {
      borrowed->discard();
      const std::string message = "job store " + redacted_ + ": the connection was lost: " + why(e, url_);
      note(message);
      throw StoreUnavailable(message);
    }
    note(why(e, url_));
    throw;
  }
}

std::unique_ptr<PgConnection> PostgresJobStore::open_connection() const {
  try {
    auto c = std::make_unique<PgConnection>(url_);
#if PQXX_VERSION_MAJOR < 7
    // libpqxx 6 reconnects a broken connection behind our back (7 never does): a session advisory lock would be
    // lost silently. A broken connection stays broken here, and the pool drops it.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
    c->c.inhibit_reactivation(true);
#pragma GCC diagnostic pop
#endif
    for (const auto& [name, sql] : statements()) c->c.prepare(name, sql);
    return c;
  } catch (const std::exception& e) {
    throw StoreUnavailable("job store " + redacted_ + ": cannot connect: " + why(e, url_));
  }
}

std::string PostgresJobStore::redacted(const std::string& url) {
  const auto scheme = url.find("://");
  if (scheme == std::string::npos) return "(a PostgreSQL URL that is not postgresql://…)";
  const auto query = url.find('?');
  std::string out = url.substr(0, query);
  const std::size_t start = scheme + 3;
  const std::size_t end = std::min(out.find('/', start), out.size());
  const std::size_t at = end == start ? std::string::npos : out.rfind('@', end - 1);
  if (at != std::string::npos && at >= start) {
    const std::size_t colon = out.find(':', start);
    if (colon < at) out.erase(colon, at - colon);  // user:password@ → user@
  }
  if (query == std::string::npos) return out;
  std::string kept;  // the parameters but password=…
  for (std::size_t p = query + 1; p <= url.size();) {
    const std::size_t next = std::min(url.find('&', p), url.size());
    const std::string param = url.substr(p, next - p);
    if (!param.empty() && !is_password_parameter(param)) kept += (kept.empty() ? "?" : "&") + param;
    p = next + 1;
  }
  return out + kept;
}

int PostgresJobStore::migrate(const std::string& url, int version) {
  if (version < 0 || version > kSchemaVersion) {
    throw std::invalid_argument("no schema version " + std::to_string(version) + " to migrate to");
  }
  const std::string name = redacted(url);
  try {
    pqxx::connection c(with_options(url));
    pqxx::work tx(c);
    tx.exec_params("SELECT pg_advisory_xact_lock($1)", kMigrationLockKey);  // other nodes migrating wait here
    tx.exec("CREATE TABLE IF NOT EXISTS texwarp_schema (version INTEGER PRIMARY KEY, "
            "applied_at TIMESTAMPTZ NOT NULL DEFAULT now())");
    const int current = stored_version(tx);
    if (current > kSchemaVersion) throw std::runtime_error(newer_schema(name, current));
    for (int v = current + 1; v <= version; ++v) {
      tx.exec(kMigrations[static_cast<std::size_t>(v - 1)]);
      tx.exec_params("INSERT INTO texwarp_schema(version) VALUES ($1)", v);
    }
    tx.commit();
    return std::max(current, version);
  } catch (const std::runtime_error& e) {
    if (std::string(e.what()).rfind("job store ", 0) == 0) throw;
    throw std::runtime_error("job store " + name + ": migration failed: " + why(e, url));
  }
}

PostgresJobStore::PostgresJobStore(const std::string& url, bool migrate_schema, int max_connections)
    : url_(with_options(url)), redacted_(redacted(url)), max_connections_(std::max(1, max_connections)) {
  if (migrate_schema) migrate(url);
  const int version = schema_version();
  if (version > kSchemaVersion) throw std::runtime_error(newer_schema(redacted_, version));
  if (version < kSchemaVersion) {
    throw std::runtime_error(
        "job store " + redacted_ +
        (version == 0 ? std::string(" has no texwarp schema") : " is at schema version " + std::to_string(version)) +
        " and this texwarpd needs version " + std::to_string(kSchemaVersion) + ": run texwarpd --store " + redacted_ +
        " --migrate");
  }
}

PostgresJobStore::~PostgresJobStore() = default;

int PostgresJobStore::schema_version() {
  return with_connection(false, [](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    return stored_version(tx);
  });
}

namespace {

Inserted insert_in(pqxx::transaction_base& tx, const NewJob& job) {
  // ON CONFLICT waits for a transaction inserting the same key and then inserts nothing: the row it made is read
  // back. A key whose job was purged in between is tried again.
  for (int attempt = 0; attempt < 3; ++attempt) {
    const std::string labels = store_rows::encode_labels(job.labels);
    const std::string kind = proto::to_string(job.kind);
    const pqxx::result inserted =
        job.idempotency_key ? tx.exec_prepared("insert", job.id, job.name, kind, job.priority, labels, job.created_ms,
                                               job.spec_json, job.body_sha256, *job.idempotency_key)
                            : tx.exec_prepared("insert", job.id, job.name, kind, job.priority, labels, job.created_ms,
                                               job.spec_json, job.body_sha256, nullptr);
    if (!inserted.empty()) return {read_row(inserted[0]), false};
    const pqxx::result existing = tx.exec_prepared("by_key", *job.idempotency_key);
    if (!existing.empty()) return {read_row(existing[0]), true};
  }
  throw std::runtime_error("job " + job.id + ": idempotency key \"" + job.idempotency_key->substr(0, 64) +
                           "\" neither inserted nor found (its job is being purged): try again");
}

}  // namespace

Inserted PostgresJobStore::insert(const NewJob& job) {
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::work tx(c);
    Inserted inserted = insert_in(tx, job);
    tx.commit();
    return inserted;
  });
}

std::vector<Inserted> PostgresJobStore::insert_batch(const std::vector<NewJob>& jobs) {
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::work tx(c);
    std::vector<Inserted> answers;
    answers.reserve(jobs.size());
    for (const auto& job : jobs) answers.push_back(insert_in(tx, job));
    tx.commit();
    return answers;
  });
}

std::optional<JobRow> PostgresJobStore::get(const std::string& id) {
  return with_connection(false, [&](pqxx::connection& c) -> std::optional<JobRow> {
    pqxx::nontransaction tx(c);
    const auto r = tx.exec_prepared("get", id);
    if (r.empty()) return std::nullopt;
    return read_row(r[0]);
  });
}

std::optional<JobRow> PostgresJobStore::find_by_idempotency_key(const std::string& key) {
  return with_connection(false, [&](pqxx::connection& c) -> std::optional<JobRow> {
    pqxx::nontransaction tx(c);
    const auto r = tx.exec_prepared("by_key", key);
    if (r.empty()) return std::nullopt;
    return read_row(r[0]);
  });
}

std::optional<std::string> PostgresJobStore::spec_json(const std::string& id) {
  return with_connection(false, [&](pqxx::connection& c) -> std::optional<std::string> {
    pqxx::nontransaction tx(c);
    const auto r = tx.exec_prepared("spec", id);
    if (r.empty()) return std::nullopt;
    return r[0][0].as<std::string>();
  });
}

std::vector<JobRow> PostgresJobStore::list(const ListQuery& query) {
  if (query.limit <= 0) return {};
  return with_connection(false, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    const std::int64_t before = query.before_seq.value_or(INT64_MAX);
    const std::string state = query.state ? proto::to_string(*query.state) : "";
    // Without labels, no containment test at all: `labels @> '{}'` could send the planner to the labels index.
    const auto r = query.labels.empty() ? tx.exec_prepared("list", before, state, query.limit)
                                        : tx.exec_prepared("list_labeled", before, state, query.limit,
                                                           store_rows::encode_labels(query.labels));
    std::vector<JobRow> rows;
    rows.reserve(r.size());
    for (const auto& row : r) rows.push_back(read_row(row));
    return rows;
  });
}

std::optional<Lease> PostgresJobStore::claim(const std::string& node_id, std::int64_t now_ms, std::int64_t lease_ms) {
  return with_connection(true, [&](pqxx::connection& c) -> std::optional<Lease> {
    pqxx::nontransaction tx(c);  // one statement: its own short transaction
    const auto r = tx.exec_prepared("claim", node_id, now_ms, lease_ms);
    if (r.empty()) return std::nullopt;
    return Lease{r[0][0].as<std::string>(), r[0][1].as<std::int64_t>(), r[0][2].as<int>(), r[0][3].as<std::string>()};
  });
}

Renewal PostgresJobStore::renew(const std::string& id, std::int64_t epoch, int progress, std::int64_t now_ms,
                                std::int64_t lease_ms) {
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    const auto r = tx.exec_prepared("renew", id, epoch, now_ms + lease_ms, progress);
    Renewal renewal;
    if (!r.empty()) {
      renewal.held = true;
      renewal.cancel_requested = r[0][0].as<bool>();
    }
    return renewal;
  });
}

bool PostgresJobStore::finish(const std::string& id, std::int64_t epoch, proto::JobState state, std::int64_t now_ms,
                              int progress, const std::string& error_json, const std::string& result_json,
                              const std::string& result_folder) {
  store_rows::require_final_state(state);
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    const auto r = tx.exec_prepared("finish", id, epoch, proto::to_string(state), now_ms, progress, error_json,
                                    result_json, result_folder);
    return r.affected_rows() == 1;
  });
}

bool PostgresJobStore::release(const std::string& id, std::int64_t epoch) {
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    return tx.exec_prepared("release", id, epoch).affected_rows() == 1;
  });
}

CancelOutcome PostgresJobStore::request_cancel(const std::string& id, std::int64_t now_ms) {
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::work tx(c);
    const auto r = tx.exec_params("SELECT state FROM jobs WHERE id = $1 FOR UPDATE", id);
    if (r.empty()) return CancelOutcome::kNotFound;
    const proto::JobState state = store_rows::decode_state(r[0][0].as<std::string>(), "jobs.state of job " + id);
    CancelOutcome outcome = CancelOutcome::kAlreadyFinal;
    if (state == proto::JobState::kQueued) {
      tx.exec_params("UPDATE jobs SET state = 'canceled', cancel_requested = true, finished_ms = $2 WHERE id = $1", id,
                     now_ms);
      outcome = CancelOutcome::kCanceled;
    } else if (state == proto::JobState::kRunning) {
      tx.exec_params("UPDATE jobs SET cancel_requested = true WHERE id = $1", id);
      outcome = CancelOutcome::kRequested;
    }
    tx.commit();
    return outcome;
  });
}

Reclaimed PostgresJobStore::reclaim_expired(std::int64_t now_ms, int max_attempts,
                                            const std::optional<std::string>& node_id) {
  // $1: the node whose leases are all dead, or now (every lease that expired before it). A lease without an expiry
  // has expired.
  const std::string dead = node_id ? "state = 'running' AND node_id = $1"
                                   : "state = 'running' AND (lease_expires_ms IS NULL OR lease_expires_ms < $1)";
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::work tx(c);
    const auto run = [&](const std::string& sql, auto&&... more) {
      return node_id ? tx.exec_params(sql, *node_id, more...) : tx.exec_params(sql, now_ms, more...);
    };
    Reclaimed r;
    r.canceled =
        static_cast<int>(run("UPDATE jobs SET state = 'canceled', finished_ms = $2, lease_expires_ms = NULL WHERE " +
                                 dead + " AND cancel_requested",
                             now_ms)
                             .affected_rows());
    r.failed = static_cast<int>(run("UPDATE jobs SET state = 'failed', finished_ms = $2, error = $3, "
                                    "lease_expires_ms = NULL WHERE " +
                                        dead + " AND attempts >= $4",
                                    now_ms, store_rows::attempts_exhausted_error(max_attempts), max_attempts)
                                    .affected_rows());
    const auto requeued =
        run("WITH q AS (UPDATE jobs SET state = 'queued', started_ms = NULL, progress = 0, lease_expires_ms = NULL "
            "WHERE " +
            dead + " RETURNING id, seq) SELECT id FROM q ORDER BY seq");
    for (const auto& row : requeued) r.requeued.push_back(row[0].as<std::string>());
    tx.commit();
    return r;
  });
}

PurgeOutcome PostgresJobStore::purge(const std::string& id) {
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::work tx(c);
    const auto r = tx.exec_params("SELECT state FROM jobs WHERE id = $1 FOR UPDATE", id);
    if (r.empty()) return PurgeOutcome::kNotFound;
    if (!proto::is_terminal(store_rows::decode_state(r[0][0].as<std::string>(), "jobs.state of job " + id))) {
      return PurgeOutcome::kNotFinished;
    }
    tx.exec_params("DELETE FROM jobs WHERE id = $1", id);
    tx.commit();
    return PurgeOutcome::kPurged;
  });
}

std::vector<std::string> PostgresJobStore::delete_finished_before(std::int64_t cutoff_ms) {
  return with_connection(true, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    const auto r = tx.exec_params(std::string("WITH d AS (DELETE FROM jobs WHERE ") + kFinished +
                                      " AND finished_ms < $1 RETURNING id, seq) SELECT id FROM d ORDER BY seq",
                                  cutoff_ms);
    std::vector<std::string> ids;
    ids.reserve(r.size());
    for (const auto& row : r) ids.push_back(row[0].as<std::string>());
    return ids;
  });
}

std::int64_t PostgresJobStore::count(proto::JobState state) {
  return with_connection(false, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    return tx.exec_prepared("count", proto::to_string(state))[0][0].as<std::int64_t>();
  });
}

FinishedSince PostgresJobStore::finished_since(std::int64_t since_ms) {
  return with_connection(false, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    const auto r = tx.exec_prepared("finished_since", since_ms);
    FinishedSince out;
    out.count = r[0][0].as<std::int64_t>();
    if (!r[0][1].is_null()) out.oldest_ms = r[0][1].as<std::int64_t>();
    return out;
  });
}

void PostgresJobStore::register_node(const NodeInfo& node) {
  with_connection(true, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    tx.exec_params(
        "INSERT INTO nodes(id, address, version, workers, pid, started_ms, last_seen_ms, running) "
        "VALUES ($1, $2, $3, $4, $5, $6, $7, $8) ON CONFLICT (id) DO UPDATE SET address = excluded.address, "
        "version = excluded.version, workers = excluded.workers, pid = excluded.pid, started_ms = excluded.started_ms, "
        "last_seen_ms = excluded.last_seen_ms, running = excluded.running",
        node.id, node.address, node.version, node.workers, node.pid, node.started_ms, node.last_seen_ms, node.running);
  });
}

void PostgresJobStore::heartbeat_node(const std::string& node_id, std::int64_t now_ms, int running) {
  with_connection(true, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    tx.exec_prepared("heartbeat", node_id, now_ms, running);
  });
}

void PostgresJobStore::remove_node(const std::string& node_id) {
  with_connection(true, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    tx.exec_params("DELETE FROM nodes WHERE id = $1", node_id);
  });
}

std::vector<NodeInfo> PostgresJobStore::nodes() {
  return with_connection(false, [&](pqxx::connection& c) {
    pqxx::nontransaction tx(c);
    const auto r =
        tx.exec("SELECT id, address, version, workers, pid, started_ms, last_seen_ms, running FROM nodes ORDER BY id");
    std::vector<NodeInfo> nodes;
    for (const auto& row : r) {
      nodes.push_back({row[0].as<std::string>(), row[1].as<std::string>(), row[2].as<std::string>(), row[3].as<int>(),
                       row[4].as<std::int64_t>(), row[5].as<std::int64_t>(), row[6].as<std::int64_t>(),
                       row[7].as<int>()});
    }
    return nodes;
  });
}

std::unique_ptr<MaintenanceLock> PostgresJobStore::try_maintenance_lock() {
  // A connection of its own, held by the lock: a session lock lives as long as its connection.
  auto c = open_connection();
  try {
    pqxx::nontransaction tx(c->c);
    if (!tx.exec_params("SELECT pg_try_advisory_lock($1)", kMaintenanceLockKey)[0][0].as<bool>()) return nullptr;
  } catch (const std::exception& e) {
    if (connection_lost(e, c->c)) {
      throw StoreUnavailable("job store " + redacted_ + ": the connection was lost: " + why(e, url_));
    }
    throw;
  }
  return std::make_unique<PostgresMaintenanceLock>(std::move(c));
}

namespace {
constexpr auto kWriteProbeInterval = std::chrono::seconds(2);
}  // namespace

std::string PostgresJobStore::health() {
  try {
    with_connection(false, [](pqxx::connection& c) {
      pqxx::nontransaction tx(c);
      tx.exec("SELECT COUNT(*) FROM texwarp_schema");
    });
  } catch (const std::exception& e) {
    return "failing: " + why(e, url_);
  }
  {
    std::lock_guard lock(health_mutex_);
    if (write_error_.empty()) return "ok";
    // The last write failed: a write that changes nothing says whether it still does, at most every few seconds.
    const auto now = std::chrono::steady_clock::now();
    if (now - last_write_probe_ < kWriteProbeInterval) return "failing: " + write_error_;
    last_write_probe_ = now;
  }
  try {
    with_connection(true, [](pqxx::connection& c) {
      pqxx::nontransaction tx(c);
      tx.exec("UPDATE texwarp_schema SET applied_at = applied_at WHERE version = (SELECT MAX(version) FROM "
              "texwarp_schema)");
    });
  } catch (const std::exception&) {
  }
  std::lock_guard lock(health_mutex_);
  return write_error_.empty() ? "ok" : "failing: " + write_error_;
}

}  // namespace texwarp::server
