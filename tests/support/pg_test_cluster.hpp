// Tests against a real PostgreSQL (scripts/pg_test_cluster.sh): the shared test cluster's URL (CTest's `postgres`
// fixture starts it; TEXWARP_PG_TEST_DIR names its folder), a fresh database on it per test, and private clusters
// a test may stop and start (the database going away under a store).
#pragma once

#include <sys/types.h>
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
  explicit PgTestDatabase(std::string cluster_url);
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

// A cluster of its own in `dir` (scripts/pg_test_cluster.sh start DIR [--tcp PORT] [--durable]), stopped and removed
// when destroyed — also when a test removed `dir` first (the server may live in a /tmp folder the script chose).
// `durable`: fsync on (benchmarks), as a production server runs.
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
  void read_server_pid();
  std::filesystem::path dir_;
  int tcp_port_;
  bool durable_;
  std::string url_;
  std::string cluster_dir_;  // where the script put the server (DIR/cluster_dir's content)
  pid_t server_pid_ = 0;     // the running server's postmaster (0 while paused)
};

}  // namespace texwarp::testing
