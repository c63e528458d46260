// JobWatchers: local wake-ups for requests waiting on a job (GET /v1/jobs/{id}?wait=S). Whoever changes a job on
// this node (a worker claiming or finishing it, a cancel) calls changed(id); each watcher of that job is called (on
// the changing thread: it must only post work elsewhere). Changes made by other nodes are seen by re-reading the
// store.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

namespace texwarp::server {

class JobWatchers {
 public:
  // Calls `wake` at each change of job `id` until the returned token is destroyed.
  std::shared_ptr<void> watch(const std::string& id, std::function<void()> wake);
  void changed(const std::string& id);
  std::size_t count() const;

 private:
  mutable std::mutex mutex_;
  std::uint64_t next_ = 0;
  std::multimap<std::string, std::pair<std::uint64_t, std::function<void()>>> watchers_;
};

}  // namespace texwarp::server
