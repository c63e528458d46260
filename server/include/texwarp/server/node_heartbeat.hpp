// NodeHeartbeat: one thread per node that, every --heartbeat-s, renews the leases this node's workers hold (storing
// their progress, and handing back what the store said: a cancel requested on any node, a lost lease), records the
// node's own heartbeat, and — with a shared store — reclaims the expired leases of any node (their jobs queued
// again, or failed after --max-attempts). The node registers when it starts and leaves at a clean stop.
#pragma once

#include <thread>

#include "texwarp/server/job_store.hpp"
#include "texwarp/server/job_workers.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/stop_signal.hpp"
#include "texwarp/server/work_signal.hpp"

namespace texwarp::server {

class NodeHeartbeat {
 public:
  NodeHeartbeat(const ServerConfig& config, JobStore& store, JobWorkers& workers, WorkSignal& work);
  ~NodeHeartbeat() { stop(false); }
  NodeHeartbeat(const NodeHeartbeat&) = delete;
  NodeHeartbeat& operator=(const NodeHeartbeat&) = delete;

  // Registers the node (retrying while the store is unreachable, until `give_up` is set) and starts the thread.
  void start(const NodeInfo& node, StopSignal& give_up);
  // Stops the thread; `leave`: removes the node from the registry (a clean shutdown).
  void stop(bool leave);
  // One heartbeat now (the thread's work).
  void beat();
  const std::string& node_id() const { return node_.id; }

 private:
  const ServerConfig& config_;
  JobStore& store_;
  JobWorkers& workers_;
  WorkSignal& work_;
  NodeInfo node_;
  StopSignal stop_;
  std::thread thread_;
  bool failing_ = false;  // the last heartbeat failed (logged once per episode)
};

}  // namespace texwarp::server
