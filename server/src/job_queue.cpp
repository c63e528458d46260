// FIFO of job ids for the workers: see job_queue.hpp.
#include "texwarp/server/job_queue.hpp"

namespace texwarp::server {

void JobQueue::push(std::string id) {
  {
    std::lock_guard lock(mutex_);
    ids_.push_back(std::move(id));
  }
  ready_.notify_one();
}

std::optional<std::string> JobQueue::pop() {
  std::unique_lock lock(mutex_);
  ready_.wait(lock, [this] { return closed_ || !ids_.empty(); });
  if (closed_) return std::nullopt;
  std::string id = std::move(ids_.front());
  ids_.pop_front();
  return id;
}

void JobQueue::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  ready_.notify_all();
}

std::size_t JobQueue::size() const {
  std::lock_guard lock(mutex_);
  return ids_.size();
}

}  // namespace texwarp::server
