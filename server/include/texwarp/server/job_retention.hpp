// JobRetention: what the data folder keeps, done by one node at a time (the store's maintenance lock). Orphaned
// result folders are removed at start and periodically: a folder under results/ is kept iff a succeeded row names
// it as its result_folder, or it is the temporary (.tmp-<job>-<E>) or just-published (<job>.<E>) folder of a job
// running under lease epoch E — so another node's live run is never touched. With --retention-hours finished jobs
// older than that are deleted with their files.
#pragma once

#include <cstddef>
#include <thread>

#include "texwarp/server/job_store.hpp"
#include "texwarp/server/result_folders.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/stop_signal.hpp"

namespace texwarp::server {

class JobRetention {
 public:
  JobRetention(const ServerConfig& config, JobStore& store, const ResultFolders& results, StopSignal& stop);
  ~JobRetention() { join(); }
  JobRetention(const JobRetention&) = delete;
  JobRetention& operator=(const JobRetention&) = delete;

  // Removes orphaned result folders, when this node gets the maintenance lock; how many (0 without the lock).
  std::size_t remove_orphans();
  // Starts the periodic sweep (orphans, and retention when configured).
  void start();
  // Waits for the sweep to end (once the stop signal is set).
  void join();

 private:
  void sweep_main();
  std::size_t remove_orphans_locked();
  std::size_t delete_expired_locked();

  const ServerConfig& config_;
  JobStore& store_;
  const ResultFolders& results_;
  StopSignal& stop_;
  std::thread sweep_;
};

}  // namespace texwarp::server
