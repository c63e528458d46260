// NodeStatus: one texwarpd node of a farm as GET /v1/nodes shows it (where it listens, its version, workers, process,
// when it started and was last seen, whether it is alive, the jobs it runs), and NodeList: the route's answer.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace texwarp::proto {

struct NodeStatus {
  std::string id;       // --node-id (default HOST:PORT)
  std::string address;  // where its API listens
  std::string version;
  int workers = 0;
  std::int64_t pid = 0;
  std::string started_at;    // RFC 3339 UTC with milliseconds
  std::string last_seen_at;  // its last heartbeat
  bool alive = false;        // seen within 3 heartbeats
  int running = 0;           // jobs it held leases on at its last heartbeat
};

struct NodeList {
  std::vector<NodeStatus> nodes;
};

}  // namespace texwarp::proto
