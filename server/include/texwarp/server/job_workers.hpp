// JobWorkers: the threads that run jobs, never an I/O thread. Each takes a queued job, marks it running, runs it
// (runner::run_job with progress and cancellation through RunControl), publishes its results (ResultFolders) and
// records its end; while the store is full it waits with backoff. Also: cancellation (of queued and running
// jobs), running jobs' progress, the default device, opened once (its state for /readyz), and shutdown's grace.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/server/job_queue.hpp"
#include "texwarp/server/job_store.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/result_folders.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/server_input_resolver.hpp"
#include "texwarp/server/stop_signal.hpp"

namespace texwarp::server {

struct DeviceState {
  std::string status = "starting";  // "ok" or the error of the default device
  std::string name;
};

struct Cancellation {
  JobRow row;              // the job after the request (cancel_requested set even when only kept in memory)
  bool requested = false;  // running: it ends canceled soon
};

class JobWorkers {
 public:
  JobWorkers(const ServerConfig& config, JobStore& store, Metrics& metrics, ServerInputResolver& resolver,
             JobQueue& queue, const ResultFolders& results, StopSignal& stop);
  JobWorkers(const JobWorkers&) = delete;
  JobWorkers& operator=(const JobWorkers&) = delete;

  // Opens the default device once, before the workers start: OpenCL is initialised on one thread.
  void open_default_device();
  void start();
  bool started() const { return !threads_.empty(); }
  // Once the queue is closed and the stop signal set: gives running jobs `grace_s` to finish, then cancels them
  // back to queued (they run again at the next start), and joins the workers.
  void stop(double grace_s);
  // Ends stop()'s grace now.
  void cut_grace() { grace_cut_.store(true); }

  // Cancels a queued job now, or asks a running one to stop. kNotFound, kJobFinished; kStorageFull when the request
  // cannot be stored and the job is not running here (a job running here stops even then: its end, canceled, is
  // recorded once there is space).
  Cancellation cancel(const std::string& id);
  // A job running here: its progress (percent), or nullopt.
  std::optional<int> progress(const std::string& id);
  std::size_t running_count();
  DeviceState device();

 private:
  struct RunningJob {
    std::atomic<int> progress{0};
    std::atomic<bool> cancel{false};
    std::atomic<bool> shutdown{false};
  };
  // How a run ended, as recorded in the store.
  struct Outcome {
    proto::JobState state = proto::JobState::kFailed;
    std::string error;     // problem JSON of a failed job
    std::string result;    // result manifest JSON of a succeeded one
    bool requeue = false;  // interrupted by shutdown: queued again
  };

  // Asks a job running here to stop (it ends canceled); false when it is not running here.
  bool cancel_running(const std::string& id);
  void worker_main(int index);
  void run_one(const std::string& id, runner::BackendCache& backends);
  std::shared_ptr<RunningJob> register_running(const std::string& id);
  void unregister_running(const std::string& id);
  Outcome execute(const std::string& id, int attempt, RunningJob& job, runner::BackendCache& backends);
  // Runs the job's spec into `temp` and publishes it; the result manifest's JSON.
  std::string run_and_publish(const std::string& id, const std::filesystem::path& temp, RunningJob& job,
                              runner::BackendCache& backends);
  void record(const std::string& id, const std::string& kind, RunningJob& job, Outcome& outcome, double seconds);
  // Runs `write` (a store write for job `id`) until it succeeds; while the disk is full, waits with backoff and
  // runs `between` before each new try. False when the server stops first; any other error is thrown.
  bool retry_while_full(const std::string& id, const std::function<void()>& write,
                        const std::function<void()>& between = {});
  void set_device(DeviceState state);

  const ServerConfig& config_;
  JobStore& store_;
  Metrics& metrics_;
  ServerInputResolver& resolver_;
  JobQueue& queue_;
  const ResultFolders& results_;
  StopSignal& stop_;
  std::vector<std::thread> threads_;
  std::atomic<bool> grace_cut_{false};

  std::mutex running_mutex_;
  std::map<std::string, std::shared_ptr<RunningJob>> running_;

  std::mutex device_mutex_;
  DeviceState device_;
};

}  // namespace texwarp::server
