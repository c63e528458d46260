// PostgreSQL databases and clusters for the farm tests: see farm_database.hpp.
#include "farm_database.hpp"

#include <gtest/gtest.h>

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace texwarp::testing {

namespace fs = std::filesystem;

namespace {

std::string shell_word(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs a shell command; throws (and fails the test) with its output when it exits non-zero.
void run(const std::string& command, const fs::path& log) {
  const int status = std::system((command + " >>" + shell_word(log.string()) + " 2>&1").c_str());
  if (status != 0) {
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    ADD_FAILURE() << "`" << command << "` failed (" << status << "):\n" << text.str();
    throw std::runtime_error("command failed: " + command);
  }
}

// PostgreSQL's server programs (initdb, pg_ctl): Debian keeps them out of PATH.
std::string pg_program(const std::string& name) {
  for (const char* version : {"15", "16", "17", "14", "13"}) {
    const fs::path p = fs::path("/usr/lib/postgresql") / version / "bin" / name;
    if (fs::exists(p)) return p.string();
  }
  return name;
}

// As the unprivileged `postgres` user when the tests run as root (PostgreSQL refuses to run as root).
std::string as_cluster_user(const std::string& command) {
  return ::geteuid() == 0 ? "runuser -u postgres -- " + command : command;
}

unsigned short free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof addr;
  if (fd < 0 || ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    if (fd >= 0) ::close(fd);
    throw std::runtime_error("no free loopback port");
  }
  ::close(fd);
  return ntohs(addr.sin_port);
}

std::string database_name() {
  static int counter = 0;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = "farm_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + "_" +
                     (info ? std::string(info->name()) : std::string("test"));
  for (char& c : name) {
    const auto u = static_cast<unsigned char>(c);
    c = std::isalnum(u) ? static_cast<char>(std::tolower(u)) : '_';
  }
  return name.substr(0, 63);
}

}  // namespace

FarmDatabase::FarmDatabase() : name_(database_name()) {
  const char* admin = std::getenv("TEXWARP_TEST_PG_URL");
  if (admin == nullptr || *admin == '\0') {
    ADD_FAILURE() << "TEXWARP_TEST_PG_URL is not set (the CTest fixture `postgres` sets it)";
    throw std::runtime_error("no test PostgreSQL");
  }
  admin_url_ = admin;
  const fs::path log = fs::temp_directory_path() / ("texwarp-" + name_ + "-psql.log");
  run("psql " + shell_word(admin_url_) + " -v ON_ERROR_STOP=1 -q -c " + shell_word("CREATE DATABASE " + name_), log);
  fs::remove(log);
  const auto slash = admin_url_.rfind('/');
  url_ = admin_url_.substr(0, slash == std::string::npos || slash < 12 ? admin_url_.size() : slash) + "/" + name_;
}

FarmDatabase::~FarmDatabase() {
  const std::string command = "psql " + shell_word(admin_url_) + " -q -c " +
                              shell_word("DROP DATABASE IF EXISTS " + name_ + " WITH (FORCE)") + " >/dev/null 2>&1";
  [[maybe_unused]] const int ignored = std::system(command.c_str());
}

PrivatePostgres::PrivatePostgres(fs::path dir) : dir_(std::move(dir)), port_(free_port()) {
  fs::create_directories(dir_);
  if (::geteuid() == 0) run("chown postgres " + shell_word(dir_.string()), dir_ / "setup.log");
  run(as_cluster_user(pg_program("initdb") + " -D " + shell_word((dir_ / "data").string()) +
                      " -A trust -U postgres --no-sync"),
      dir_ / "setup.log");
  start();
  run("psql " + shell_word("postgresql://postgres@127.0.0.1:" + std::to_string(port_) + "/postgres") +
          " -v ON_ERROR_STOP=1 -q -c 'CREATE DATABASE texwarp'",
      dir_ / "setup.log");
}

PrivatePostgres::~PrivatePostgres() {
  if (running_) {
    const std::string command = as_cluster_user(pg_program("pg_ctl") + " -D " + shell_word((dir_ / "data").string()) +
                                                " -m immediate -w stop") +
                                " >/dev/null 2>&1";
    [[maybe_unused]] const int ignored = std::system(command.c_str());
  }
  std::error_code ignored;
  fs::remove_all(dir_, ignored);
}

std::string PrivatePostgres::url() const {
  return "postgresql://postgres@127.0.0.1:" + std::to_string(port_) + "/texwarp";
}

void PrivatePostgres::pg_ctl(const std::string& args) const {
  run(as_cluster_user(pg_program("pg_ctl") + " -D " + shell_word((dir_ / "data").string()) + " " + args),
      dir_ / "pg_ctl.log");
}

void PrivatePostgres::stop() {
  pg_ctl("-m fast -w -t 60 stop");
  running_ = false;
}

void PrivatePostgres::start() {
  const std::string options = "-p " + std::to_string(port_) + " -k " + dir_.string() +
                              " -c listen_addresses=127.0.0.1 -c fsync=off -c max_connections=200";
  pg_ctl("-w -t 60 -l " + shell_word((dir_ / "server.log").string()) + " -o " + shell_word(options) + " start");
  running_ = true;
}

}  // namespace texwarp::testing
