// Fresh databases for the job store suite: see job_store_backends.hpp.
#include "job_store_backends.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "pg_test_cluster.hpp"
#include "test_folder.hpp"
#include "texwarp/server/postgres_job_store.hpp"
#include "texwarp/server/sqlite_job_store.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;

class SqliteDatabase final : public StoreDatabase {
 public:
  SqliteDatabase() : dir_(texwarp::testing::test_folder_path("sqlite")) {}
  ~SqliteDatabase() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  std::unique_ptr<server::JobStore> open() override {
    return std::make_unique<server::SqliteJobStore>(dir_ / "jobs.sqlite3");
  }

 private:
  fs::path dir_;
};

// A fresh database on the shared test cluster; every store object migrates it (the first one creates the schema).
class PostgresDatabase final : public StoreDatabase {
 public:
  std::unique_ptr<server::JobStore> open() override {
    return std::make_unique<server::PostgresJobStore>(database_.url(), /*migrate=*/true);
  }

 private:
  PgTestDatabase database_;
};

}  // namespace

std::unique_ptr<StoreDatabase> make_store_database(StoreBackend backend) {
  switch (backend) {
    case StoreBackend::kSqlite:
      return std::make_unique<SqliteDatabase>();
    case StoreBackend::kPostgres:
      return std::make_unique<PostgresDatabase>();
  }
  throw std::logic_error("no such store backend");
}

}  // namespace texwarp::testing
