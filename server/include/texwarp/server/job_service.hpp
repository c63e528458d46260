// JobService: the service behind the HTTP routes. Accepts jobs (decode, idempotency, admission against the bounded
// queue, pre-checks, durable insert), answers status, lists, cancels and results, and runs jobs on its worker
// threads (never on an I/O thread) with progress and cancellation through RunControl. On start it recovers what a
// previous process left (running jobs re-queued or failed, orphaned results removed) and opens the default device
// once. Results are published by renaming a folder, then recorded; a full disk is 507, and a job's end waits for it.
#pragma once

#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_result.hpp"
#include "texwarp/proto/job_status.hpp"
#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/server/blob_store.hpp"
#include "texwarp/server/job_queue.hpp"
#include "texwarp/server/job_store.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/server_input_resolver.hpp"

namespace texwarp::server {

struct SubmitResult {
  proto::JobStatus status;
  bool replayed = false;  // an Idempotency-Key seen before with the same body: the original job
};

struct CancelResult {
  proto::JobStatus status;
  bool requested = false;  // running: cancellation requested, the job ends canceled soon
};

struct Readiness {
  bool ready = false;
  std::string status = "not_ready";  // "ready", "not_ready" or "draining" (shutting down: send no new work)
  nlohmann::json checks;
};

class JobService {
 public:
  JobService(const ServerConfig& config, JobStore& store, BlobStore& blobs, Metrics& metrics);
  ~JobService();
  JobService(const JobService&) = delete;
  JobService& operator=(const JobService&) = delete;

  // Recovers the store's jobs, removes orphaned result folders, opens the default device (its state for /readyz)
  // and starts the workers (and the retention sweep when configured).
  void start();
  // From now on new jobs are refused with 503 and /readyz says "draining" (503).
  void begin_drain();
  // Stops taking queued jobs, gives running ones `grace_s` to finish, then cancels them back to queued (they
  // run again at the next start), and joins the workers.
  void shutdown(double grace_s);
  // Ends shutdown's grace now (a second SIGTERM/SIGINT): running jobs stop and go back to the queue.
  void cut_grace() { grace_cut_.store(true); }
  bool draining() const { return draining_.load(); }

  // ApiError for every refusal (400 malformed JSON, 422 invalid job or reused key, 429 queue full, 503 draining,
  // 507 the server's disk is full).
  SubmitResult submit(const std::string& body, const std::optional<std::string>& idempotency_key);
  // While a request with this key is being processed, a second one gets 409: the token releases the key.
  std::shared_ptr<void> claim_idempotency_key(const std::string& key);

  proto::JobStatus status(const std::string& id);  // 404 when unknown
  proto::JobPage list(const std::string& cursor, int limit, std::optional<proto::JobState> state);
  // 404 unknown, 409 already finished, 507 the disk is full and the job is not running here (a running job stops
  // even when its cancel request cannot be stored).
  CancelResult cancel(const std::string& id);
  proto::JobResult result(const std::string& id);  // 404 unknown, 409 not succeeded
  // The path of one of a succeeded job's files (404 when it has no such file).
  std::filesystem::path result_file(const std::string& id, const std::string& name, std::string* media_type,
                                    std::string* sha256);

  proto::BlobInfo adopt_blob(const std::filesystem::path& temp_file);
  BlobStore& blobs() { return blobs_; }

  Readiness readiness();
  std::vector<Gauge> gauges();
  // Seconds a client should wait before retrying when the queue is full.
  int retry_after_s();

 private:
  struct RunningJob {
    std::atomic<int> progress{0};
    std::atomic<bool> cancel{false};
    std::atomic<bool> shutdown{false};
  };

  void open_default_device();
  void worker_main(int index);
  void run_one(const std::string& id, runner::BackendCache& backends);
  // Runs `write` (a store write for job `id`) until it succeeds; while the disk is full, waits with backoff and
  // runs `between` before each new try. False when the server stops first; any other error is thrown.
  bool retry_while_full(const std::string& id, const std::function<void()>& write,
                        const std::function<void()>& between = {});
  void retention_main();
  proto::JobStatus to_status(const JobRow& row);
  std::filesystem::path result_dir(const std::string& id) const;

  const ServerConfig& config_;
  JobStore& store_;
  BlobStore& blobs_;
  Metrics& metrics_;
  ServerInputResolver resolver_;
  JobQueue queue_;
  std::filesystem::path results_;
  std::vector<std::thread> workers_;
  std::thread retention_;
  std::atomic<bool> draining_{false};
  std::atomic<bool> stopping_{false};
  std::atomic<bool> grace_cut_{false};
  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;

  std::mutex running_mutex_;
  std::map<std::string, std::shared_ptr<RunningJob>> running_;

  std::mutex keys_mutex_;
  std::set<std::string> keys_in_flight_;

  std::mutex device_mutex_;
  std::string device_status_ = "starting";  // "ok" or the error of the default device
  std::string device_name_;
};

}  // namespace texwarp::server
