// Several texwarpd nodes on one store for the farm tests: see farm_nodes.hpp.
#include "farm_nodes.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <csignal>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace texwarp::testing {

namespace {

std::string number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

// A shell word: single quotes, with embedded single quotes closed and escaped.
std::string shell_word(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

int migrate_store(const std::string& store_url, std::string* output) {
  const std::string command = shell_word(TEXWARPD_BINARY) + " --store " + shell_word(store_url) + " --migrate 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("popen failed: " + command);
  std::string text;
  std::array<char, 4096> buf{};
  while (const std::size_t n = std::fread(buf.data(), 1, buf.size(), pipe)) text.append(buf.data(), n);
  const int status = ::pclose(pipe);
  if (output != nullptr) *output = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

FarmNodes::FarmNodes(std::filesystem::path data_dir, std::string store_url, int count, FarmOptions options)
    : data_dir_(std::move(data_dir)), store_url_(std::move(store_url)), options_(std::move(options)) {
  std::filesystem::create_directories(data_dir_);
  std::string output;
  const int code = migrate_store(store_url_, &output);
  if (code != 0) {
    ADD_FAILURE() << "texwarpd --migrate exited " << code << ":\n" << output;
    throw std::runtime_error("texwarpd --migrate failed");
  }
  for (int i = 0; i < count; ++i) add(store_url_);
}

int FarmNodes::add(const std::string& store_url) {
  const int i = size();
  urls_.push_back(store_url);
  past_.emplace_back();
  nodes_.push_back(std::make_unique<ServerProcess>(data_dir_, args(i)));
  ports_.push_back(nodes_.back()->port());
  return i;
}

std::vector<std::string> FarmNodes::args(int i) const {
  std::vector<std::string> a = {"--store",           urls_.at(static_cast<std::size_t>(i)),
                                "--node-id",         node_id(i),
                                "--lease-s",         number(options_.lease_s),
                                "--heartbeat-s",     number(options_.heartbeat_s),
                                "--poll-ms",         std::to_string(options_.poll_ms),
                                "--workers",         std::to_string(options_.workers),
                                "--max-attempts",    std::to_string(options_.max_attempts),
                                "--threads-per-job", "1"};
  a.insert(a.end(), options_.extra_args.begin(), options_.extra_args.end());
  return a;
}

int FarmNodes::index_of(const std::string& id) const {
  for (int i = 0; i < static_cast<int>(nodes_.size()); ++i) {
    if (node_id(i) == id) return i;
  }
  return -1;
}

void FarmNodes::kill(int i) {
  node(i).signal(SIGKILL);
  EXPECT_EQ(node(i).wait_exit(20), 128 + SIGKILL) << node_id(i) << " did not die of SIGKILL";
}

void FarmNodes::restart(int i) {
  const auto k = static_cast<std::size_t>(i);
  if (nodes_[k]->running()) kill(i);
  past_[k].push_back(std::move(nodes_[k]));
  nodes_[k] = std::make_unique<ServerProcess>(ListenPort{ports_[k]}, data_dir_, args(i));
}

std::string FarmNodes::logs(int i) const {
  const auto k = static_cast<std::size_t>(i);
  std::string all;
  for (const auto& p : past_[k]) all += p->log();
  return all + nodes_[k]->log();
}

}  // namespace texwarp::testing
