// Local wake-ups of requests waiting on a job: see job_watchers.hpp.
#include "texwarp/server/job_watchers.hpp"

#include <vector>

namespace texwarp::server {

std::shared_ptr<void> JobWatchers::watch(const std::string& id, std::function<void()> wake) {
  std::uint64_t serial = 0;
  {
    std::lock_guard lock(mutex_);
    serial = ++next_;
    watchers_.emplace(id, std::make_pair(serial, std::move(wake)));
  }
  return std::shared_ptr<void>(nullptr, [this, id, serial](void*) {
    std::lock_guard lock(mutex_);
    const auto [first, last] = watchers_.equal_range(id);
    for (auto it = first; it != last; ++it) {
      if (it->second.first == serial) {
        watchers_.erase(it);
        break;
      }
    }
  });
}

void JobWatchers::changed(const std::string& id) {
  std::vector<std::function<void()>> wakes;
  {
    std::lock_guard lock(mutex_);
    const auto [first, last] = watchers_.equal_range(id);
    for (auto it = first; it != last; ++it) wakes.push_back(it->second.second);
  }
  for (const auto& wake : wakes) wake();
}

std::size_t JobWatchers::count() const {
  std::lock_guard lock(mutex_);
  return watchers_.size();
}

}  // namespace texwarp::server
