// JobWorkers: the threads that run jobs, never an I/O thread. Each claims the next job from the store (a lease with
// its fencing epoch), runs it (runner::run_job with progress and cancellation through RunControl), publishes its
// results (ResultFolders: temporary folder, then one rename) and records its end presenting the epoch; a fenced end
// (the lease was taken over) removes its own folder. While the store is full or unreachable it backs off and
// retries. Idle workers sleep on the WorkSignal or --poll-ms. The node's heartbeat (NodeHeartbeat) renews the
// leases held here and hands back what it learnt (renewed()): a cancel requested on any node, a lost lease. Also:
// the default device, opened once (its state for /readyz), and shutdown's grace (unfinished jobs are released).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/server/job_store.hpp"
#include "texwarp/server/job_watchers.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/result_folders.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/server_input_resolver.hpp"
#include "texwarp/server/stop_signal.hpp"
#include "texwarp/server/work_signal.hpp"

namespace texwarp::server {

struct DeviceState {
  std::string status = "starting";  // "ok" or the error of the default device
  std::string name;
};

// A lease a worker of this node holds, as the heartbeat renews it.
struct HeldLease {
  std::string job_id;
  std::int64_t epoch = 0;
  int progress = 0;  // percent
};

class JobWorkers {
 public:
  JobWorkers(const ServerConfig& config, JobStore& store, Metrics& metrics, ServerInputResolver& resolver,
             WorkSignal& work, JobWatchers& watchers, const ResultFolders& results, StopSignal& stop);
  JobWorkers(const JobWorkers&) = delete;
  JobWorkers& operator=(const JobWorkers&) = delete;

  // Starts the workers, claiming as node `node_id`, and returns at once: a thread of its own first opens the default
  // device (OpenCL is initialised on one thread) and builds and launches every kernel variant, which with a cold
  // kernel cache takes tens of seconds, then starts them. Meanwhile the server answers (/livez, submissions queue)
  // and /readyz says not ready, its device "starting".
  void start(const std::string& node_id);
  bool started() const { return started_.load(); }
  // Once the stop signal is set (no more claims): gives running jobs `grace_s` to finish, then stops them and
  // releases their leases (queued again, the attempt given back), and joins the workers.
  void stop(double grace_s);
  // Ends stop()'s grace now.
  void cut_grace() { grace_cut_.store(true); }

  // The leases held here now.
  std::vector<HeldLease> held_leases();
  // What the heartbeat's renewal of a lease said: a lost lease stops the job (nothing about it is recorded), a cancel
  // request stops it as canceled.
  void renewed(const std::string& id, std::int64_t epoch, const Renewal& renewal);
  // Stops job `id` if it runs here (it ends canceled); false when it does not run here.
  bool cancel_running(const std::string& id);
  // A job running here: its progress (percent), or nullopt.
  std::optional<int> progress(const std::string& id);
  std::size_t running_count();
  DeviceState device();

 private:
  struct RunningJob {
    std::int64_t epoch = 0;
    std::atomic<int> progress{0};
    std::atomic<bool> cancel{false};
    std::atomic<bool> shutdown{false};
    std::atomic<bool> lost{false};  // the lease was lost: stop, record nothing
  };
  // How a run ended, as recorded in the store.
  struct Outcome {
    proto::JobState state = proto::JobState::kFailed;
    std::string error;          // problem JSON of a failed job
    std::string result;         // result manifest JSON of a succeeded one
    std::string result_folder;  // the published folder of a succeeded one ("<job>.<epoch>")
    bool requeue = false;       // interrupted by shutdown: released, queued again
    bool lost = false;          // the lease was lost while it ran: nothing is recorded
  };

  void worker_main(int index);
  // The next lease, or nullopt (nothing queued, or the store failed: backed off already).
  std::optional<Lease> claim_next(std::chrono::milliseconds& backoff);
  void run_one(const Lease& lease, runner::BackendCache& backends);
  std::shared_ptr<RunningJob> register_running(const std::string& id, std::int64_t epoch);
  void unregister_running(const std::string& id, const RunningJob* job);
  Outcome execute(const Lease& lease, const proto::JobSpec& spec, RunningJob& job, runner::BackendCache& backends);
  // Runs the spec into the lease's temporary folder and publishes it; the result manifest's JSON.
  std::string run_and_publish(const Lease& lease, const proto::JobSpec& spec, RunningJob& job,
                              runner::BackendCache& backends, std::string* folder);
  void record(const Lease& lease, const std::string& kind, RunningJob& job, Outcome& outcome, double seconds);
  // Runs `write` (a store write about job `id`) until it succeeds; while the disk is full or the store unreachable,
  // waits with backoff and runs `between` before each new try (which may end the retries by returning false). False
  // when the server stops first or `between` gives up; any other error is thrown.
  bool retry_store(const std::string& id, const std::function<void()>& write,
                   const std::function<bool()>& between = {});
  void set_device(DeviceState state);
  void open_default_device();

  const ServerConfig& config_;
  JobStore& store_;
  Metrics& metrics_;
  ServerInputResolver& resolver_;
  WorkSignal& work_;
  JobWatchers& watchers_;
  const ResultFolders& results_;
  StopSignal& stop_;
  std::string node_id_;
  std::thread starter_;  // opens the device, then starts threads_ (which only stop() touches once it is joined)
  std::atomic<bool> started_{false};
  std::vector<std::thread> threads_;
  std::atomic<bool> grace_cut_{false};

  std::mutex running_mutex_;
  std::map<std::string, std::shared_ptr<RunningJob>> running_;
  bool interrupt_new_ = false;  // shutdown's grace is over: a job claimed now is released at once

  std::mutex device_mutex_;
  DeviceState device_;
};

}  // namespace texwarp::server
