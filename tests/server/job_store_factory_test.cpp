// --store's values: the embedded SQLite store by default, PostgreSQL for a postgresql:// or postgres:// URL, and a
// clear refusal of anything else (never echoing what could be a password).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "pg_test_cluster.hpp"
#include "test_folder.hpp"
#include "texwarp/server/job_store_factory.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;

TEST(JobStoreFactory, SqliteIsTheDefaultInTheDataFolder) {
  const fs::path dir = texwarp::testing::test_folder_path("store");
  for (const std::string value : {"", "sqlite"}) {
    const auto store = open_job_store(value, dir, false);
    EXPECT_EQ(store->backend(), "sqlite");
    EXPECT_EQ(store->schema_version(), 2);
    EXPECT_TRUE(fs::exists(dir / "jobs.sqlite3"));
  }
}

TEST(JobStoreFactory, RefusesOtherStoresWithoutEchoingThem) {
  const fs::path dir = texwarp::testing::test_folder_path("store");
  for (const std::string value : {"mysql://root:s3cret@db/farm", "SQLite", "postgresql:/x", "s3cret"}) {
    try {
      open_job_store(value, dir, true);
      FAIL() << value;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("--store must be \"sqlite\" or a postgresql://"), std::string::npos) << what;
      if (value.find("://") != std::string::npos) {
        EXPECT_EQ(what.find("s3cret"), std::string::npos) << what;
      }
    }
  }
}

TEST(PostgresJobStoreFactory, OpensPostgresqlAndPostgresUrls) {
  testing::PgTestDatabase db;
  const fs::path dir = texwarp::testing::test_folder_path("store");
  auto store = open_job_store(db.url(), dir, true);
  EXPECT_EQ(store->backend(), "postgresql");
  EXPECT_EQ(store->schema_version(), 2);
  EXPECT_FALSE(fs::exists(dir / "jobs.sqlite3"));
  const std::string short_scheme = "postgres://" + db.url().substr(std::string("postgresql://").size());
  EXPECT_EQ(open_job_store(short_scheme, dir, false)->backend(), "postgresql");
}

}  // namespace
}  // namespace texwarp::server
