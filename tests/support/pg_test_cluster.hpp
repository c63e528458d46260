// Tests against a real PostgreSQL (scripts/pg_test_cluster.sh): the shared test cluster's URL (CTest's `postgres`
// fixture starts it; TEXWARP_PG_TEST_DIR names its folder), a fresh database on it per test, and private clusters
// a test may stop and start (the database going away under a store).
#pragma once

#include <filesystem>
#include <string>

namespace texwarp::testing {

// The URL of the shared test cluster, read from $TEXWARP_PG_TEST_DIR/url (default: <build>/pg-test/url). Throws
// std::runtime_error saying how to start one when it is missing or does not answer.
std::string pg_test_url();

// `url` with its database replaced by `database`.
std::string pg_url_with_database(const std::string& url, const std::string& database);

// CREATE DATABASE t_<random> on the shared cluster; dropped (its connections ended) when destroyed.
class PgTestDatabase {
 public:
  PgTestDatabase();
  explicit PgTestDatabase(const std::string& cluster_url);
  ~PgTestDatabase();
  PgTestDatabase(const PgTestDatabase&) = delete;
  PgTestDatabase& operator=(const PgTestDatabase&) = delete;

  const std::string& url() const { return url_; }
  const std::string& name() const { return name_; }

 private:
  std::string cluster_url_;
  std::string name_;
  std::string url_;
};

// A cluster of its own in `dir` (scripts/pg_test_cluster.sh start DIR [--tcp PORT] [--durable]), removed when
// destroyed. `durable`: fsync on (benchmarks), as a production server runs.
class PgPrivateCluster {
 public:
  explicit PgPrivateCluster(std::filesystem::path dir, int tcp_port = 0, bool durable = false);
  ~PgPrivateCluster();
  PgPrivateCluster(const PgPrivateCluster&) = delete;
  PgPrivateCluster& operator=(const PgPrivateCluster&) = delete;

  const std::string& url() const { return url_; }
  void pause();   // the server stops; its data stays
  void resume();  // started again, same URL

 private:
  std::string script(const std::string& command) const;
  std::filesystem::path dir_;
  int tcp_port_;
  bool durable_;
  std::string url_;
};

}  // namespace texwarp::testing
