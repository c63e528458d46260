// Test PostgreSQL clusters and databases: see pg_test_cluster.hpp.
#include "pg_test_cluster.hpp"

#include <pqxx/pqxx>

#include <sys/wait.h>
#include <array>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <stdexcept>
#include <thread>
#include <utility>

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;

// Runs a shell command; its standard output, or throws with its output when it fails.
std::string run(const std::string& command) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("cannot run " + command);
  std::string output;
  std::array<char, 4096> buffer{};
  while (const std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe)) output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw std::runtime_error(command + " failed:\n" + output);
  return output;
}

std::string last_line(std::string text) {
  while (!text.empty() && text.back() == '\n') text.pop_back();
  const auto newline = text.rfind('\n');
  return newline == std::string::npos ? text : text.substr(newline + 1);
}

}  // namespace

std::string pg_test_url() {
  const char* env = std::getenv("TEXWARP_PG_TEST_DIR");
  const fs::path dir = env != nullptr && *env != '\0' ? fs::path(env) : fs::path(TEXWARP_PG_TEST_DIR);
  std::ifstream in(dir / "url");
  std::string url;
  if (!std::getline(in, url) || url.empty()) {
    throw std::runtime_error("no test PostgreSQL cluster at " + dir.string() +
                             " (ctest starts one with the `postgres` fixture; by hand: scripts/pg_test_cluster.sh "
                             "start " +
                             dir.string() + ")");
  }
  return url;
}

std::string pg_url_with_database(const std::string& url, const std::string& database) {
  const auto scheme = url.find("://");
  if (scheme == std::string::npos) throw std::invalid_argument("not a postgresql:// URL: " + url);
  const auto query = url.find('?', scheme);
  const auto path = url.find('/', scheme + 3);
  const auto authority_end = std::min(path, query);
  const std::string rest = query == std::string::npos ? std::string() : url.substr(query);
  return url.substr(0, authority_end) + "/" + database + rest;
}

PgTestDatabase::PgTestDatabase() : PgTestDatabase(pg_test_url()) {}

PgTestDatabase::PgTestDatabase(std::string cluster_url) : cluster_url_(std::move(cluster_url)) {
  std::random_device random;
  std::mt19937_64 bits((static_cast<std::uint64_t>(random()) << 32) ^ random());
  char name[32];
  std::snprintf(name, sizeof name, "t_%016llx", static_cast<unsigned long long>(bits()));
  name_ = name;
  pqxx::connection c(cluster_url_);
  pqxx::nontransaction tx(c);
  tx.exec("CREATE DATABASE " + name_);
  url_ = pg_url_with_database(cluster_url_, name_);
}

PgTestDatabase::~PgTestDatabase() {
  try {
    pqxx::connection c(cluster_url_);
    pqxx::nontransaction tx(c);
    tx.exec("DROP DATABASE IF EXISTS " + name_ + " WITH (FORCE)");
  } catch (const std::exception&) {
    // The cluster went away: so did the database.
  }
}

PgPrivateCluster::PgPrivateCluster(fs::path dir, int tcp_port, bool durable)
    : dir_(std::move(dir)), tcp_port_(tcp_port), durable_(durable) {
  url_ = last_line(script("start"));
  std::ifstream pointer(dir_ / "cluster_dir");
  std::getline(pointer, cluster_dir_);
  read_server_pid();
}

PgPrivateCluster::~PgPrivateCluster() {
  try {
    if (!fs::exists(dir_ / "cluster_dir") && !cluster_dir_.empty()) {  // the test removed DIR: say where it runs
      fs::create_directories(dir_);
      std::ofstream(dir_ / "cluster_dir") << cluster_dir_ << "\n";
    }
    script("stop");
  } catch (const std::exception&) {
  }
  // A test that removed the cluster's own folder left a server the script cannot see (no data/PG_VERSION): it is
  // ended by its PID (SIGQUIT: PostgreSQL's immediate shutdown; SIGKILL if it lingers).
  if (server_pid_ > 0 && ::kill(server_pid_, 0) == 0) {
    ::kill(server_pid_, SIGQUIT);
    for (int i = 0; i < 100 && ::kill(server_pid_, 0) == 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (::kill(server_pid_, 0) == 0) ::kill(server_pid_, SIGKILL);
  }
}

void PgPrivateCluster::pause() {
  script("pause");
  server_pid_ = 0;
}

void PgPrivateCluster::resume() {
  script("start");
  read_server_pid();
}

void PgPrivateCluster::read_server_pid() {
  std::ifstream pid_file(fs::path(cluster_dir_) / "data" / "postmaster.pid");  // its first line is the PID
  long pid = 0;
  if (pid_file >> pid) server_pid_ = static_cast<pid_t>(pid);
}

std::string PgPrivateCluster::script(const std::string& command) const {
  std::string line = std::string(TEXWARP_PG_TEST_SCRIPT) + " " + command + " '" + dir_.string() + "'";
  if (command == "start" && tcp_port_ != 0) line += " --tcp " + std::to_string(tcp_port_);
  if (command == "start" && durable_) line += " --durable";
  return run(line);
}

}  // namespace texwarp::testing
