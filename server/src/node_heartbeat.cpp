// The node's heartbeat: see node_heartbeat.hpp.
#include "texwarp/server/node_heartbeat.hpp"

#include <chrono>

#include "texwarp/server/json_log.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {

NodeHeartbeat::NodeHeartbeat(const ServerConfig& config, JobStore& store, JobWorkers& workers, WorkSignal& work)
    : config_(config), store_(store), workers_(workers), work_(work) {}

void NodeHeartbeat::start(const NodeInfo& node, StopSignal& give_up) {
  node_ = node;
  for (auto delay = std::chrono::milliseconds(100);; delay = std::min(delay * 2, std::chrono::milliseconds(2000))) {
    try {
      store_.register_node(node_);
      break;
    } catch (const StoreUnavailable& e) {
      log_event(LogLevel::kWarn, "cannot register the node yet; retrying", {{"node", node_.id}, {"error", e.what()}});
      if (give_up.wait_for(delay)) return;
    }
  }
  thread_ = std::thread([this] {
    const auto period = std::chrono::duration<double>(config_.heartbeat_s);
    while (!stop_.wait_for(period)) beat();
  });
}

void NodeHeartbeat::stop(bool leave) {
  stop_.set();
  if (thread_.joinable()) thread_.join();
  if (!leave || node_.id.empty()) return;
  try {
    store_.remove_node(node_.id);
  } catch (const std::exception& e) {
    log_event(LogLevel::kWarn, "could not remove the node from the registry",
              {{"node", node_.id}, {"error", e.what()}});
  }
  node_.id.clear();
}

void NodeHeartbeat::beat() {
  const auto lease_ms = static_cast<std::int64_t>(config_.lease_s * 1000.0);
  try {
    const auto leases = workers_.held_leases();
    for (const HeldLease& l : leases) {
      const Renewal r = store_.renew(l.job_id, l.epoch, l.progress, now_ms(), lease_ms);
      workers_.renewed(l.job_id, l.epoch, r);
    }
    store_.heartbeat_node(node_.id, now_ms(), static_cast<int>(leases.size()));
    if (!config_.sqlite_store()) {
      const Reclaimed r = store_.reclaim_expired(now_ms(), config_.max_attempts);
      if (!r.requeued.empty() || r.canceled > 0 || r.failed > 0) {
        log_event(LogLevel::kInfo, "reclaimed expired leases",
                  {{"requeued", r.requeued.size()}, {"canceled", r.canceled}, {"failed", r.failed}});
        if (!r.requeued.empty()) work_.notify();
      }
    }
    if (failing_) log_event(LogLevel::kInfo, "heartbeats reach the store again", {{"node", node_.id}});
    failing_ = false;
  } catch (const std::exception& e) {
    if (!failing_) {
      log_event(LogLevel::kWarn, "heartbeat failed; leases are renewed again once the store answers",
                {{"node", node_.id}, {"error", e.what()}});
    }
    failing_ = true;
  }
}

}  // namespace texwarp::server
