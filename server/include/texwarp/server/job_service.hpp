// JobService: the service as the routes see it, a facade over its parts: JobAdmission (how jobs get in),
// JobWorkers (how they run, stop and end), JobRetention (what the data folder keeps). It wires them to one queue, one
// set of result folders and one stop signal, orders start-up (recovery, clean-up, device, workers) and shutdown,
// and answers the reads: a job's status, lists, results, blobs, readiness and gauges.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_result.hpp"
#include "texwarp/proto/job_status.hpp"
#include "texwarp/server/blob_store.hpp"
#include "texwarp/server/job_admission.hpp"
#include "texwarp/server/job_queue.hpp"
#include "texwarp/server/job_retention.hpp"
#include "texwarp/server/job_store.hpp"
#include "texwarp/server/job_workers.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/result_folders.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/server_input_resolver.hpp"
#include "texwarp/server/stop_signal.hpp"

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
  // From now on new jobs are refused (kShuttingDown) and /readyz says "draining" (503).
  void begin_drain() { admission_.begin_drain(); }
  // Stops taking queued jobs, gives running ones `grace_s` to finish, then cancels them back to queued (they
  // run again at the next start), and joins the workers.
  void shutdown(double grace_s);
  // Ends shutdown's grace now (a second SIGTERM/SIGINT): running jobs stop and go back to the queue.
  void cut_grace() { workers_.cut_grace(); }
  bool draining() const { return admission_.draining(); }

  // JobAdmission::submit's refusals.
  SubmitResult submit(const std::string& body, const std::optional<std::string>& idempotency_key);
  std::shared_ptr<void> claim_idempotency_key(const std::string& key) { return admission_.claim_idempotency_key(key); }

  proto::JobStatus status(const std::string& id);  // kNotFound
  // kBadQuery for a cursor this server did not give out.
  proto::JobPage list(const std::string& cursor, int limit, std::optional<proto::JobState> state);
  // JobWorkers::cancel's refusals.
  CancelResult cancel(const std::string& id);
  proto::JobResult result(const std::string& id);  // kNotFound, kNoResult (not succeeded)
  // The path of one of a succeeded job's files (kNotFound when it has no such file).
  std::filesystem::path result_file(const std::string& id, const std::string& name, std::string* media_type,
                                    std::string* sha256);

  proto::BlobInfo adopt_blob(const std::filesystem::path& temp_file);  // kStorageFull
  BlobStore& blobs() { return blobs_; }

  Readiness readiness();
  std::vector<Gauge> gauges();

 private:
  proto::JobStatus to_status(const JobRow& row);

  const ServerConfig& config_;
  JobStore& store_;
  BlobStore& blobs_;
  Metrics& metrics_;
  ServerInputResolver resolver_;
  JobQueue queue_;
  ResultFolders results_;
  StopSignal stop_;
  JobAdmission admission_;
  JobWorkers workers_;
  JobRetention retention_;
};

}  // namespace texwarp::server
