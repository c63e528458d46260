// PostgreSQL for the farm tests: a fresh database on the shared test cluster (the CTest fixture `postgres`), and a
// private throw-away cluster for the one test that stops and restarts the database server under the nodes.
#pragma once

#include <filesystem>
#include <string>

namespace texwarp::testing {

// A fresh, empty database on the test cluster, named for the running test; dropped when destroyed.
class FarmDatabase {
 public:
  FarmDatabase();
  ~FarmDatabase();
  FarmDatabase(const FarmDatabase&) = delete;
  FarmDatabase& operator=(const FarmDatabase&) = delete;

  // postgresql://… for texwarpd --store.
  const std::string& url() const { return url_; }

 private:
  std::string admin_url_;
  std::string name_;
  std::string url_;
};

// A PostgreSQL cluster of its own in `dir` on a free loopback port (initdb as the `postgres` user when the tests
// run as root), for tests that stop and start the database server; stopped and removed when destroyed.
class PrivatePostgres {
 public:
  explicit PrivatePostgres(std::filesystem::path dir);
  ~PrivatePostgres();
  PrivatePostgres(const PrivatePostgres&) = delete;
  PrivatePostgres& operator=(const PrivatePostgres&) = delete;

  // The database `texwarp` on it.
  std::string url() const;
  unsigned short port() const { return port_; }
  void stop();   // pg_ctl stop -m fast: connections are cut
  void start();  // on the same port

 private:
  void pg_ctl(const std::string& args) const;

  std::filesystem::path dir_;
  unsigned short port_ = 0;
  bool running_ = false;
};

}  // namespace texwarp::testing
