// JobService: the service as the routes see it, a facade over its parts: JobAdmission (how jobs get in), JobWorkers
// (how they run, stop and end), NodeHeartbeat (this node's leases and registration), JobRetention (what the data
// folder keeps). It wires them to one store, one set of result folders, one wake-up signal and one stop signal,
// orders start-up (recovery, clean-up, device, node, workers) and shutdown, and answers the reads: a job's status
// (the progress of a job running on another node from its row), lists, results (from the row's result folder),
// deletes (cancel or purge), nodes, blobs, readiness and gauges.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_result.hpp"
#include "texwarp/proto/job_status.hpp"
#include "texwarp/proto/node_status.hpp"
#include "texwarp/server/blob_store.hpp"
#include "texwarp/server/job_admission.hpp"
#include "texwarp/server/job_retention.hpp"
#include "texwarp/server/job_store.hpp"
#include "texwarp/server/job_watchers.hpp"
#include "texwarp/server/job_workers.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/node_heartbeat.hpp"
#include "texwarp/server/result_folders.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/server_input_resolver.hpp"
#include "texwarp/server/stop_signal.hpp"
#include "texwarp/server/work_signal.hpp"

namespace texwarp::server {

struct SubmitResult {
  proto::JobStatus status;
  bool replayed = false;  // an Idempotency-Key seen before with the same body: the original job
};

struct BatchResult {
  std::vector<proto::JobStatus> jobs;  // in the batch's order
  bool replayed = false;
};

// What POST /v1/jobs/{id}:cancel or DELETE /v1/jobs/{id} did.
struct DeleteResult {
  enum class Action { kCanceled, kCancelRequested, kPurged };
  Action action = Action::kCanceled;
  proto::JobStatus status;  // the job after the request (before the purge for kPurged)
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

  // Reclaims the leases of this node's earlier life (with SQLite: every running job), removes orphaned result
  // folders, opens the default device (its state for /readyz), registers the node (id --node-id, else
  // HOSTNAME:port) and starts its heartbeat, the workers and the maintenance sweep.
  void start(unsigned short port);
  const std::string& node_id() const { return node_id_; }
  // From now on new jobs are refused (kShuttingDown) and /readyz says "draining" (503).
  void begin_drain() { admission_.begin_drain(); }
  // Stops claiming, gives running jobs `grace_s` to finish, then stops them and releases them (queued again for
  // any node), stops the heartbeat and leaves the node registry.
  void shutdown(double grace_s);
  // Ends shutdown's grace now (a second SIGTERM/SIGINT): running jobs stop and go back to the queue.
  void cut_grace() { workers_.cut_grace(); }
  bool draining() const { return admission_.draining(); }

  // JobAdmission's refusals.
  SubmitResult submit(const std::string& body, const std::optional<std::string>& idempotency_key);
  BatchResult submit_batch(const std::string& body, const std::optional<std::string>& idempotency_key);
  std::shared_ptr<void> claim_idempotency_key(const std::string& key) { return admission_.claim_idempotency_key(key); }

  proto::JobStatus status(const std::string& id);  // kNotFound
  // kBadQuery for a cursor this server did not give out.
  proto::JobPage list(const std::string& cursor, int limit, std::optional<proto::JobState> state,
                      const Labels& labels = {});
  // Cancels a queued job, asks a running one (on any node) to stop; never purges: kJobFinished (nothing changed,
  // its state in the detail) for a finished one. kNotFound; kStorageFull when a cancel cannot be stored and the job
  // does not run here.
  DeleteResult cancel(const std::string& id);
  // cancel(), but a finished job is purged (its row and files) instead of refused.
  DeleteResult remove(const std::string& id);
  proto::JobResult result(const std::string& id);  // kNotFound, kNoResult (not succeeded)
  // The path of one of a succeeded job's files (kNotFound when it has no such file).
  std::filesystem::path result_file(const std::string& id, const std::string& name, std::string* media_type,
                                    std::string* sha256);
  // Calls `wake` (from any thread) whenever this node changes job `id`, until the token is destroyed.
  std::shared_ptr<void> watch(const std::string& id, std::function<void()> wake) {
    return watchers_.watch(id, std::move(wake));
  }
  proto::NodeList nodes();

  proto::BlobInfo adopt_blob(const std::filesystem::path& temp_file);  // kStorageFull
  BlobStore& blobs() { return blobs_; }

  Readiness readiness();
  std::vector<Gauge> gauges();

 private:
  proto::JobStatus to_status(const JobRow& row);
  // What cancel() and remove() share: the cancellation done, or the row of a job that had already finished
  // (nothing changed).
  std::variant<DeleteResult, JobRow> cancel_unfinished(const std::string& id);
  // The folder a succeeded job's files are served from.
  std::filesystem::path served_folder(const JobRow& row) const;
  JobRow succeeded_row(const std::string& id);  // kNotFound, kNoResult

  const ServerConfig& config_;
  JobStore& store_;
  BlobStore& blobs_;
  Metrics& metrics_;
  ServerInputResolver resolver_;
  WorkSignal work_;
  JobWatchers watchers_;
  ResultFolders results_;
  StopSignal stop_;
  std::string node_id_;
  JobAdmission admission_;
  JobWorkers workers_;
  NodeHeartbeat heartbeat_;
  JobRetention retention_;
};

}  // namespace texwarp::server
