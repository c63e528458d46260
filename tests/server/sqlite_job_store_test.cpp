// What only the SQLite store has: a file of the first release (schema 1) migrated at open, with its succeeded jobs'
// files where they were (result_folder = id); files it must refuse; the claim served by its partial index.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "test_folder.hpp"
#include "texwarp/server/sqlite_connection.hpp"
#include "texwarp/server/sqlite_job_store.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;
using proto::JobState;

// The first release's schema and rows as it wrote them (copied here, not taken from the store's source).
void write_schema_1_file(const fs::path& file) {
  SqliteConnection db(file);
  db.exec("PRAGMA journal_mode=WAL");
  db.exec(R"sql(
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
INSERT INTO jobs(id, name, kind, state, progress, attempts, created_ms, started_ms, finished_ms, spec, body_sha256,
                 idempotency_key, result)
  VALUES ('done', 'd', 'image', 'succeeded', 100, 1, 10, 11, 12, '{"s": "done"}', 'sha-done', 'key-done',
          '{"files": []}');
INSERT INTO jobs(id, name, kind, state, progress, attempts, created_ms, started_ms, finished_ms, spec, body_sha256,
                 error)
  VALUES ('broke', 'b', 'mesh', 'failed', 20, 1, 20, 21, 22, '{"s": "broke"}', 'sha-broke', '{"type": "x"}');
INSERT INTO jobs(id, name, kind, state, progress, attempts, created_ms, started_ms, spec, body_sha256)
  VALUES ('was-running', 'r', 'image', 'running', 40, 1, 30, 31, '{"s": "was-running"}', 'sha-r');
INSERT INTO jobs(id, name, kind, state, created_ms, spec, body_sha256)
  VALUES ('waiting', 'w', 'image', 'queued', 40, '{"s": "waiting"}', 'sha-w');
)sql");
}

std::string meta_version(const fs::path& file) {
  SqliteConnection db(file);
  auto q = db.prepare("SELECT value FROM meta WHERE key = 'schema_version'");
  EXPECT_TRUE(q.step());
  return q.text(0);
}

TEST(SqliteJobStore, MigratesAFileOfSchema1KeepingEveryRow) {
  const fs::path file = texwarp::testing::test_folder_path("store") / "jobs.sqlite3";
  write_schema_1_file(file);
  EXPECT_EQ(meta_version(file), "1");
  SqliteJobStore store(file);
  EXPECT_EQ(store.schema_version(), 2);
  EXPECT_EQ(meta_version(file), "2");

  const auto done = store.get("done");
  ASSERT_TRUE(done);
  EXPECT_EQ(done->state, JobState::kSucceeded);
  EXPECT_EQ(done->result_folder, "done");  // the first release's layout: results/<id>/
  EXPECT_EQ(done->result_json, R"({"files": []})");
  EXPECT_EQ(done->finished_ms, 12);
  EXPECT_EQ(done->priority, 0);
  EXPECT_TRUE(done->labels.empty());
  EXPECT_EQ(done->node_id, "");
  EXPECT_EQ(done->lease_epoch, 0);
  const auto broke = store.get("broke");
  EXPECT_EQ(broke->kind, proto::JobKind::kMesh);
  EXPECT_EQ(broke->result_folder, "");
  EXPECT_EQ(broke->error_json, R"({"type": "x"})");
  EXPECT_EQ(*store.spec_json("waiting"), R"({"s": "waiting"})");

  // The idempotency key still answers with its job.
  NewJob again;
  again.id = "other";
  again.spec_json = "{}";
  again.body_sha256 = "sha-other";
  again.idempotency_key = "key-done";
  const Inserted answer = store.insert(again);
  EXPECT_TRUE(answer.existed);
  EXPECT_EQ(answer.row.id, "done");

  // A job the old server left running holds no lease: the first reclaim takes it back, whatever the time.
  const Reclaimed reclaimed = store.reclaim_expired(0, 3);
  EXPECT_EQ(reclaimed.requeued, std::vector<std::string>{"was-running"});
  const auto lease = store.claim("n1", 100, 1000);
  ASSERT_TRUE(lease);
  EXPECT_EQ(lease->job_id, "was-running");
  EXPECT_EQ(lease->attempt, 2);
  EXPECT_EQ(lease->epoch, 1);
  EXPECT_EQ(store.claim("n1", 100, 1000)->job_id, "waiting");
}

TEST(SqliteJobStore, OpeningAMigratedFileAgainChangesNothing) {
  const fs::path file = texwarp::testing::test_folder_path("store") / "jobs.sqlite3";
  write_schema_1_file(file);
  { SqliteJobStore store(file); }
  SqliteJobStore store(file);
  EXPECT_EQ(store.schema_version(), 2);
  EXPECT_EQ(store.get("done")->result_folder, "done");
  EXPECT_EQ(store.count(JobState::kSucceeded), 1);
}

TEST(SqliteJobStore, ANewFileStartsAtTheNewestSchema) {
  const fs::path file = texwarp::testing::test_folder_path("store") / "jobs.sqlite3";
  SqliteJobStore store(file);
  EXPECT_EQ(store.schema_version(), JobStore::kSchemaVersion);
  EXPECT_EQ(store.backend(), "sqlite");
  EXPECT_TRUE(store.healthy());
}

TEST(SqliteJobStore, RefusesANewerSchemaNamingTheFile) {
  const fs::path file = texwarp::testing::test_folder_path("store") / "jobs.sqlite3";
  { SqliteJobStore store(file); }
  {
    SqliteConnection db(file);
    db.exec("UPDATE meta SET value = '3' WHERE key = 'schema_version'");
  }
  try {
    SqliteJobStore store(file);
    FAIL() << "opened a schema-3 file";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find("version 3"), std::string::npos) << what;
    EXPECT_NE(what.find("newer"), std::string::npos) << what;
  }
}

TEST(SqliteJobStore, RefusesAFileThatIsNotAJobStore) {
  const fs::path dir = texwarp::testing::test_folder_path("store");
  std::ofstream(dir / "garbage.sqlite3") << std::string(8192, 'x');
  try {
    SqliteJobStore store(dir / "garbage.sqlite3");
    FAIL() << "opened garbage";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "garbage.sqlite3").string()), std::string::npos) << e.what();
  }
  {
    SqliteConnection db(dir / "other.sqlite3");
    db.exec("CREATE TABLE jobs (x INTEGER)");
  }
  try {
    SqliteJobStore store(dir / "other.sqlite3");
    FAIL() << "opened another program's jobs table";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no schema version"), std::string::npos) << e.what();
  }
}

TEST(SqliteJobStore, TheClaimIndexServesTheClaimOrderWithoutASort) {
  const fs::path file = texwarp::testing::test_folder_path("store") / "jobs.sqlite3";
  { SqliteJobStore store(file); }
  SqliteConnection db(file);
  // The claim names the index (INDEXED BY fails the statement when the index cannot serve it): it must give the
  // claim's order as it is, without sorting the queued rows.
  auto q = db.prepare("EXPLAIN QUERY PLAN SELECT seq FROM jobs INDEXED BY jobs_claim WHERE state = 'queued' "
                      "ORDER BY priority DESC, seq LIMIT 1");
  std::string plan;
  while (q.step()) plan += q.text(3) + "\n";
  EXPECT_NE(plan.find("USING INDEX jobs_claim"), std::string::npos) << plan;
  EXPECT_EQ(plan.find("TEMP B-TREE"), std::string::npos) << plan;
}

}  // namespace
}  // namespace texwarp::server
