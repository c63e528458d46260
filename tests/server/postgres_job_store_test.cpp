// What only the PostgreSQL store has: versioned migrations (and the refusal to run on an older schema without
// --migrate), errors that name the store without its password, the claim's index, and the database going away
// under a running store (StoreUnavailable, then a new call works once it is back).
#include <gtest/gtest.h>
#include <unistd.h>

#include <pqxx/pqxx>

#include <barrier>
#include <filesystem>
#include <string>
#include <thread>

#include "pg_test_cluster.hpp"
#include "texwarp/server/postgres_job_store.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;
using proto::JobState;

NewJob job(const std::string& id) {
  NewJob j;
  j.id = id;
  j.spec_json = "{}";
  j.body_sha256 = "sha";
  j.created_ms = 1;
  return j;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PostgresJobStore, RefusesAnAbsentOrOlderSchemaUnlessMigrated) {
  testing::PgTestDatabase db;
  std::string error = error_of([&] { PostgresJobStore store(db.url(), /*migrate=*/false); });
  EXPECT_NE(error.find("has no texwarp schema"), std::string::npos) << error;
  EXPECT_NE(error.find("run texwarpd --store " + db.url() + " --migrate"), std::string::npos) << error;

  EXPECT_EQ(PostgresJobStore::migrate(db.url(), 1), 1);
  error = error_of([&] { PostgresJobStore store(db.url(), false); });
  EXPECT_NE(error.find("is at schema version 1"), std::string::npos) << error;
  EXPECT_NE(error.find("needs version 2"), std::string::npos) << error;
  EXPECT_NE(error.find("--migrate"), std::string::npos) << error;

  PostgresJobStore migrated(db.url(), /*migrate=*/true);
  EXPECT_EQ(migrated.schema_version(), 2);
  PostgresJobStore store(db.url(), false);  // now it may
  EXPECT_EQ(store.schema_version(), 2);
  EXPECT_EQ(store.backend(), "postgresql");
  pqxx::connection c(db.url());
  pqxx::nontransaction tx(c);
  const auto rows = tx.exec("SELECT version, applied_at IS NOT NULL FROM texwarp_schema ORDER BY version");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0][0].as<int>(), 1);
  EXPECT_EQ(rows[1][0].as<int>(), 2);
  EXPECT_TRUE(rows[1][1].as<bool>());
  EXPECT_EQ(PostgresJobStore::migrate(db.url()), 2);  // again: nothing to do
  EXPECT_EQ(tx.exec("SELECT COUNT(*) FROM texwarp_schema")[0][0].as<int>(), 2);
}

TEST(PostgresJobStore, MigratesVersion1RowsLikeSqlite) {
  testing::PgTestDatabase db;
  PostgresJobStore::migrate(db.url(), 1);
  {
    pqxx::connection c(db.url());
    pqxx::work tx(c);
    tx.exec("INSERT INTO jobs(id, kind, state, created_ms, finished_ms, spec, body_sha256, result) VALUES "
            "('done', 'image', 'succeeded', 1, 2, '{}', 's', '{\"files\": []}'), "
            "('broke', 'image', 'failed', 1, 2, '{}', 's', ''), "
            "('was-running', 'image', 'running', 1, NULL, '{}', 's', '')");
    tx.commit();
  }
  PostgresJobStore store(db.url(), true);
  EXPECT_EQ(store.get("done")->result_folder, "done");
  EXPECT_EQ(store.get("done")->result_json, R"({"files": []})");
  EXPECT_EQ(store.get("broke")->result_folder, "");
  EXPECT_EQ(store.reclaim_expired(0, 3).requeued, std::vector<std::string>{"was-running"});
}

TEST(PostgresJobStore, RefusesANewerSchema) {
  testing::PgTestDatabase db;
  PostgresJobStore::migrate(db.url());
  {
    pqxx::connection c(db.url());
    pqxx::nontransaction tx(c);
    tx.exec("INSERT INTO texwarp_schema(version) VALUES (3)");
  }
  for (const bool migrate : {false, true}) {
    const std::string error = error_of([&] { PostgresJobStore store(db.url(), migrate); });
    EXPECT_NE(error.find("schema version 3, newer than this texwarpd's 2"), std::string::npos) << error;
  }
}

TEST(PostgresJobStore, NodesMigratingAtOnceMigrateOnce) {
  testing::PgTestDatabase db;
  constexpr int kNodes = 4;
  std::barrier start(kNodes);
  std::vector<std::string> errors(kNodes);
  std::vector<std::thread> threads;
  threads.reserve(kNodes);
  for (int i = 0; i < kNodes; ++i) {
    threads.emplace_back([&, i] {
      start.arrive_and_wait();
      errors[i] = error_of([&] { PostgresJobStore store(db.url(), true); });
    });
  }
  for (auto& t : threads) t.join();
  for (const auto& e : errors) EXPECT_EQ(e, "(no error)");
  pqxx::connection c(db.url());
  pqxx::nontransaction tx(c);
  EXPECT_EQ(tx.exec("SELECT COUNT(*) FROM texwarp_schema")[0][0].as<int>(), 2);
}

TEST(PostgresJobStore, RedactsPasswordsFromUrls) {
  EXPECT_EQ(PostgresJobStore::redacted("postgresql://alice:s3cret@db.example:5433/farm?sslmode=require"),
            "postgresql://alice@db.example:5433/farm?sslmode=require");
  EXPECT_EQ(PostgresJobStore::redacted("postgres://alice:p@ss:w@rd@db/farm"), "postgres://alice@db/farm");
  EXPECT_EQ(PostgresJobStore::redacted("postgresql://db/farm?password=s3cret&sslmode=require&user=bob"),
            "postgresql://db/farm?sslmode=require&user=bob");
  EXPECT_EQ(PostgresJobStore::redacted("postgresql://db/farm?password=s3cret"), "postgresql://db/farm");
  EXPECT_EQ(PostgresJobStore::redacted("postgresql:///farm?host=/run/pg"), "postgresql:///farm?host=/run/pg");
  EXPECT_EQ(PostgresJobStore::redacted("postgresql://alice@/farm"), "postgresql://alice@/farm");
  // libpq decodes a parameter's name and takes the last of a repeated one: no spelling of password= is kept.
  EXPECT_EQ(PostgresJobStore::redacted("postgresql://db/farm?pass%77ord=s3cret&sslmode=require"),
            "postgresql://db/farm?sslmode=require");
  EXPECT_EQ(PostgresJobStore::redacted("postgresql://db/farm?password=a&PASSWORD=b&%70assword=c"),
            "postgresql://db/farm?PASSWORD=b");
}

TEST(PostgresJobStore, AnUnreachableServerOrABadUrlIsNamedWithoutItsPassword) {
  const std::string unreachable = "postgresql://alice:s3cret@/farm?host=/nonexistent-texwarp-socket-dir";
  std::string error = error_of([&] { PostgresJobStore store(unreachable, false); });
  EXPECT_NE(error.find("job store postgresql://alice@/farm?host=/nonexistent-texwarp-socket-dir"), std::string::npos)
      << error;
  EXPECT_NE(error.find("cannot connect"), std::string::npos) << error;
  EXPECT_EQ(error.find("s3cret"), std::string::npos) << error;

  const std::string bad = "postgresql://alice:s3cret@localhost:notaport/farm";
  error = error_of([&] { PostgresJobStore store(bad, true); });
  EXPECT_NE(error.find("job store postgresql://alice@localhost:notaport/farm"), std::string::npos) << error;
  EXPECT_EQ(error.find("s3cret"), std::string::npos) << error;

  const std::string bad_param = "postgresql://alice@/farm?password=s3cret&bogus_option=1";
  error = error_of([&] { PostgresJobStore store(bad_param, true); });
  EXPECT_NE(error.find("job store postgresql://alice@/farm?bogus_option=1"), std::string::npos) << error;
  EXPECT_EQ(error.find("s3cret"), std::string::npos) << error;

  // libpq quotes the whole URI it cannot parse: an encoded parameter name, a repeated one, are scrubbed there too.
  const std::string quoted = "postgresql://[::1:5432/farm?pass%77ord=s3cret1&password=s3cret2&password=s3cret%33";
  error = error_of([&] { PostgresJobStore store(quoted, false); });
  EXPECT_NE(error.find("cannot connect"), std::string::npos) << error;
  EXPECT_EQ(error.find("s3cret"), std::string::npos) << error;
}

TEST(PostgresJobStore, TheClaimWalksItsIndexWith100000FinishedJobs) {
  testing::PgTestDatabase db;
  PostgresJobStore store(db.url(), true);
  {
    pqxx::connection c(db.url());
    pqxx::work tx(c);
    tx.exec("INSERT INTO jobs(id, kind, state, created_ms, finished_ms, spec, body_sha256) "
            "SELECT 'f' || i, 'image', 'succeeded', i, i, '{}', 's' FROM generate_series(1, 100000) AS i");
    tx.exec("ANALYZE jobs");
    tx.commit();
  }
  store.insert(job("next"));
  pqxx::connection c(db.url());
  pqxx::nontransaction tx(c);
  std::string plan;
  for (const auto& row :
       tx.exec("EXPLAIN SELECT seq FROM jobs WHERE state = 'queued' ORDER BY priority DESC, seq LIMIT 1 "
               "FOR UPDATE SKIP LOCKED")) {
    plan += row[0].as<std::string>() + "\n";
  }
  EXPECT_NE(plan.find("jobs_claim"), std::string::npos) << plan;
  EXPECT_EQ(plan.find("Sort"), std::string::npos) << plan;
  EXPECT_EQ(store.claim("n1", 1, 1000)->job_id, "next");
}

TEST(PostgresJobStore, ABrokenConnectionIsStoreUnavailableAndTheNextCallReconnects) {
  testing::PgTestDatabase db;
  PostgresJobStore store(db.url(), true);
  store.insert(job("a"));
  EXPECT_TRUE(store.get("a"));  // the pool holds an open connection now
  {
    pqxx::connection c(db.url());
    pqxx::nontransaction tx(c);
    const auto killed = tx.exec_params("SELECT COUNT(*) FROM (SELECT pg_terminate_backend(pid) FROM pg_stat_activity "
                                       "WHERE datname = $1 AND pid <> pg_backend_pid()) AS t",
                                       db.name());
    EXPECT_GE(killed[0][0].as<int>(), 1);
  }
  EXPECT_THROW(store.get("a"), StoreUnavailable);
  ASSERT_TRUE(store.get("a"));  // a new connection
  EXPECT_EQ(store.get("a")->id, "a");
  EXPECT_EQ(store.health(), "ok");
}

TEST(PostgresJobStore, WhileTheServerIsDownEveryCallIsStoreUnavailableAndItRecovers) {
  const fs::path dir = fs::temp_directory_path() / ("texwarp-pg-" + std::to_string(::getpid()) + "-down");
  testing::PgPrivateCluster cluster(dir);
  testing::PgTestDatabase db(cluster.url());
  PostgresJobStore store(db.url(), true);
  store.insert(job("a"));
  const auto lease = store.claim("n1", 1, 1000);
  ASSERT_TRUE(lease);
  EXPECT_TRUE(store.healthy());

  cluster.pause();
  EXPECT_THROW(store.renew("a", lease->epoch, 10, 2, 1000), StoreUnavailable);  // the pooled connection broke
  EXPECT_THROW(store.insert(job("b")), StoreUnavailable);                       // and no new one can be made
  EXPECT_THROW(store.claim("n1", 2, 1000), StoreUnavailable);
  EXPECT_THROW(store.try_maintenance_lock(), StoreUnavailable);
  const std::string health = store.health();
  EXPECT_EQ(health.rfind("failing: ", 0), 0u) << health;
  try {
    store.get("a");
    FAIL() << "read from a stopped server";
  } catch (const StoreUnavailable& e) {
    EXPECT_NE(std::string(e.what()).find("job store " + db.url()), std::string::npos) << e.what();
  }

  cluster.resume();
  const Renewal renewal = store.renew("a", lease->epoch, 20, 3, 1000);  // nothing was lost, nothing half-written
  EXPECT_TRUE(renewal.held);
  EXPECT_FALSE(store.get("b"));
  EXPECT_EQ(store.get("a")->progress, 20);
  EXPECT_TRUE(store.healthy());
  EXPECT_TRUE(store.try_maintenance_lock());
}

}  // namespace
}  // namespace texwarp::server
