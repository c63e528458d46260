// ServerProcess: the real texwarpd started for a test on a free loopback port (--listen 127.0.0.1:0 with a port
// file) or on a given one (to restart a server in place), its log captured to a file; killed (SIGKILL) when the
// test is done unless it already exited.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace texwarp::testing {

// A port to listen on, for a server that takes over from a previous one (its port()).
struct ListenPort {
  unsigned short port = 0;
};

// What a started server is waited for: listening (its port file), or also its device opened (texwarpd listens at
// once and opens its default device, building every kernel variant, on a thread of its own: /readyz's device check
// says "starting" until then, for tens of seconds with a cold kernel cache).
enum class AwaitStart { kDevice, kListening };

class ServerProcess {
 public:
  // Starts texwarpd with --listen 127.0.0.1:0 --data-dir `data_dir` plus `args` (and --device cpu unless they
  // name a device), and waits (≤ 20 s) until it listens, then (kDevice, ≤ 180 s more) until /readyz's device check
  // is past "starting". `env` entries "NAME=value" are added to its environment. Fails the test (and throws) if it
  // does not come up.
  // With test_defaults false it gets --listen, --data-dir and --port-file only (the server's own defaults).
  explicit ServerProcess(std::filesystem::path data_dir, const std::vector<std::string>& args = {},
                         std::vector<std::string> env = {}, bool test_defaults = true,
                         AwaitStart await = AwaitStart::kDevice);
  // The same on 127.0.0.1:`listen.port`; while that port is still taken (a previous server exiting) it tries
  // again until the 20 s are up.
  ServerProcess(ListenPort listen, std::filesystem::path data_dir, const std::vector<std::string>& args = {},
                const std::vector<std::string>& env = {}, bool test_defaults = true);
  ~ServerProcess();
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  unsigned short port() const { return port_; }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }
  pid_t pid() const { return pid_; }
  const std::filesystem::path& data_dir() const { return data_dir_; }

  void signal(int sig) const;
  // Waits for the process to exit; its exit code, 128 + signal when killed, or -1 on timeout.
  int wait_exit(double timeout_s);
  bool running();
  std::string log() const;

 private:
  // Forks and execs texwarpd with `argv`; its output goes to log_file_.
  void launch(std::vector<std::string> argv, std::vector<std::string> env);
  // Polls the port file until the server wrote its port (true) or exited or the deadline passed (false).
  bool await_port(const std::filesystem::path& port_file, std::chrono::steady_clock::time_point deadline);
  // Polls /readyz until its device check is past "starting" (true) or the server exited or 180 s passed (false).
  bool await_device();

  std::filesystem::path data_dir_;
  std::filesystem::path log_file_;
  pid_t pid_ = -1;
  unsigned short port_ = 0;
  int exit_code_ = -1;
};

// A fresh empty folder for the running test: test_folder_path("server" + suffix) (test_folder.hpp), kept when the
// test fails.
std::filesystem::path test_folder(const std::string& suffix = "");

}  // namespace texwarp::testing
