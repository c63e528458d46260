// JobRetention: what the data folder keeps. At start, result folders no job will be served from (half-written
// temporaries, folders of jobs the store no longer has) are removed; with --retention-hours a sweep thread deletes
// finished jobs older than that, with their results, until the stop signal.
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

  // Removes orphaned result folders; how many.
  std::size_t remove_orphans();
  // Starts the sweep when --retention-hours is set.
  void start();
  // Waits for the sweep to end (once the stop signal is set).
  void join();

 private:
  void sweep_main();

  const ServerConfig& config_;
  JobStore& store_;
  const ResultFolders& results_;
  StopSignal& stop_;
  std::thread sweep_;
};

}  // namespace texwarp::server
