// Starting and stopping the real texwarpd for tests: see server_process.hpp.
#include "server_process.hpp"

#include <nlohmann/json.hpp>

#include "raw_http.hpp"
#include "test_folder.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace texwarp::testing {

namespace fs = std::filesystem;

fs::path test_folder(const std::string& suffix) { return test_folder_path("server" + suffix); }

namespace {

// texwarpd's command line: --listen, --data-dir and --port-file, then --device cpu (unless `args` name a device
// or test_defaults is false), then `args`.
std::vector<std::string> server_argv(const std::string& listen, const fs::path& data_dir, const fs::path& port_file,
                                     const std::vector<std::string>& args, bool test_defaults) {
  std::vector<std::string> argv = {TEXWARPD_BINARY, "--listen",        listen, "--data-dir", data_dir.string(),
                                   "--port-file",   port_file.string()};
  if (test_defaults && std::find(args.begin(), args.end(), "--device") == args.end()) {
    argv.insert(argv.end(), {"--device", "cpu"});
  }
  argv.insert(argv.end(), args.begin(), args.end());
  return argv;
}

// Where a server's log and port file go: beside its data folder, named for it and a counter.
std::string next_tag(const fs::path& data_dir) {
  static int counter = 0;
  return data_dir.filename().string() + "-" + std::to_string(counter++);
}

}  // namespace

ServerProcess::ServerProcess(fs::path data_dir, const std::vector<std::string>& args, std::vector<std::string> env,
                             bool test_defaults, AwaitStart await)
    : data_dir_(std::move(data_dir)) {
  const fs::path run_dir = data_dir_.parent_path();
  const std::string tag = next_tag(data_dir_);
  log_file_ = run_dir / (tag + ".log");
  const fs::path port_file = run_dir / (tag + ".port");
  remove_when_passed(log_file_);  // beside the data folder, which may be the test's folder itself
  remove_when_passed(port_file);
  fs::remove(port_file);
  launch(server_argv("127.0.0.1:0", data_dir_, port_file, args, test_defaults), std::move(env));
  if (await_port(port_file, std::chrono::steady_clock::now() + std::chrono::seconds(20)) &&
      (await == AwaitStart::kListening || await_device())) {
    return;
  }
  const std::string text = log();
  signal(SIGKILL);
  wait_exit(5);
  ADD_FAILURE() << "texwarpd did not start; its log:\n" << text;
  throw std::runtime_error("texwarpd did not start");
}

bool ServerProcess::await_port(const fs::path& port_file, std::chrono::steady_clock::time_point deadline) {
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream in(port_file);
    int port = 0;
    if (in >> port && port > 0) {
      port_ = static_cast<unsigned short>(port);
      return true;
    }
    if (!running()) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

bool ServerProcess::await_device() {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(180);
  while (std::chrono::steady_clock::now() < deadline && running()) {
    try {
      const nlohmann::json ready = nlohmann::json::parse(http_request(port_, "GET", "/readyz").body);
      if (ready.at("checks").at("device").at("status") != "starting") return true;
    } catch (const std::exception&) {
      // not answering yet, or not JSON: try again
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

ServerProcess::ServerProcess(ListenPort listen, fs::path data_dir, const std::vector<std::string>& args,
                             const std::vector<std::string>& env, bool test_defaults)
    : data_dir_(std::move(data_dir)) {
  const fs::path run_dir = data_dir_.parent_path();
  const std::string tag = next_tag(data_dir_);
  log_file_ = run_dir / (tag + ".log");
  const fs::path port_file = run_dir / (tag + ".port");
  remove_when_passed(log_file_);  // beside the data folder, which may be the test's folder itself
  remove_when_passed(port_file);
  const auto argv = server_argv("127.0.0.1:" + std::to_string(listen.port), data_dir_, port_file, args, test_defaults);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline) {
    fs::remove(port_file);
    exit_code_ = -1;
    launch(argv, env);
    if (await_port(port_file, deadline)) {
      if (await_device()) return;
      break;
    }
    if (running() || log().find("cannot listen") == std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the port is still taken: try again
  }
  const std::string text = log();
  signal(SIGKILL);
  wait_exit(5);
  ADD_FAILURE() << "texwarpd did not start on port " << listen.port << "; its log:\n" << text;
  throw std::runtime_error("texwarpd did not start");
}

void ServerProcess::launch(std::vector<std::string> argv_strings, std::vector<std::string> env) {
  pid_ = ::fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    const int fd = ::open(log_file_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::close(fd);
    }
    for (auto& e : env) ::putenv(e.data());
    std::vector<char*> argv;
    argv.reserve(argv_strings.size() + 1);
    for (auto& s : argv_strings) argv.push_back(s.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
}

ServerProcess::~ServerProcess() {
  if (running()) {
    signal(SIGKILL);
    wait_exit(10);
  }
}

void ServerProcess::signal(int sig) const {
  if (pid_ > 0) ::kill(pid_, sig);
}

bool ServerProcess::running() {
  if (pid_ <= 0 || exit_code_ >= 0) return false;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return false;
  }
  return r == 0;
}

int ServerProcess::wait_exit(double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (running()) {
    if (std::chrono::steady_clock::now() >= deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return exit_code_;
}

std::string ServerProcess::log() const {
  std::ifstream in(log_file_);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace texwarp::testing
