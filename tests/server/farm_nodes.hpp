// FarmNodes: several real texwarpd processes on one PostgreSQL store and one shared data folder, each with its own
// --node-id and short leases, for the multi-node tests: kill -9, SIGSTOP/SIGCONT and restarts of a node in place
// (same port, same node id). Every incarnation's log is kept for the checks.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "server_process.hpp"

namespace texwarp::testing {

struct FarmOptions {
  double lease_s = 2;
  double heartbeat_s = 0.5;
  int poll_ms = 100;
  int workers = 1;
  int max_attempts = 3;
  std::vector<std::string> extra_args;  // added to every node's command line
};

// Runs `texwarpd --store URL --migrate` and returns its exit code; its output goes to `output` when given.
int migrate_store(const std::string& store_url, std::string* output = nullptr);

class FarmNodes {
 public:
  // Migrates the store (the test fails when that fails), then starts `count` nodes named node-1 … node-N on free
  // loopback ports, all with --data-dir `data_dir` and --store `store_url`.
  FarmNodes(std::filesystem::path data_dir, std::string store_url, int count, FarmOptions options = {});

  int size() const { return static_cast<int>(nodes_.size()); }
  ServerProcess& node(int i) { return *nodes_.at(static_cast<std::size_t>(i)); }
  unsigned short port(int i) const { return ports_.at(static_cast<std::size_t>(i)); }
  // NOLINTNEXTLINE(readability-convert-member-functions-to-static): asked of a farm, as port(i) and node(i) are
  std::string node_id(int i) const { return "node-" + std::to_string(i + 1); }
  // The index of the node with this --node-id, or -1.
  int index_of(const std::string& node_id) const;
  const std::filesystem::path& data_dir() const { return data_dir_; }
  const std::string& store_url() const { return store_url_; }

  // Starts one more node (node-<size()+1>) on this store URL (e.g. the same database through a PausableProxy);
  // returns its index.
  int add(const std::string& store_url);

  // SIGKILL and reap; the node stays down until restart(i).
  void kill(int i);
  // Starts node i again on its port with its node id (a node that is still running is killed first).
  void restart(int i);
  bool up(int i) { return node(i).running(); }

  // Every log this node wrote, all incarnations, in order.
  std::string logs(int i) const;

 private:
  std::vector<std::string> args(int i) const;

  std::filesystem::path data_dir_;
  std::string store_url_;
  FarmOptions options_;
  std::vector<std::unique_ptr<ServerProcess>> nodes_;
  std::vector<unsigned short> ports_;
  std::vector<std::string> urls_;                                  // each node's --store
  std::vector<std::vector<std::unique_ptr<ServerProcess>>> past_;  // earlier incarnations, kept for their logs
};

}  // namespace texwarp::testing
