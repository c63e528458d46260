// libtexwarp_client: the C++ client of texwarpd for DCC plugins and pipeline tools. Uploads textures and meshes,
// submits jobs one by one or as a batch (with an Idempotency-Key, so retries never run a job twice), lists them by
// state and labels, waits (long-poll) with a progress callback, fetches results, cancels, purges, lists the farm's
// nodes. Every call returns Result<T>, never throws. Each call retries within a time budget
// (ClientOptions::retry_budget, 60 s): refused or broken connections, 429, 502, 503 and 504 with jittered
// exponential backoff or after the server's Retry-After, so a farm task outlives a server restart; other 4xx
// answers are returned at once. Thread safety: one Client may be used from any number of threads at once (each
// call borrows a keep-alive connection from the Client's pool, opening another when all are busy); only moving,
// assigning or destroying it must not overlap a call. Callbacks run on the calling thread.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "texwarp/client/result.hpp"
#include "texwarp/client/stop_token.hpp"
#include "texwarp/proto/blob_info.hpp"
#include "texwarp/proto/export.hpp"
#include "texwarp/proto/job_batch.hpp"
#include "texwarp/proto/job_report.hpp"
#include "texwarp/proto/job_result.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/job_status.hpp"
#include "texwarp/proto/node_status.hpp"

namespace texwarp::client {

struct ClientOptions {
  std::string server = "http://127.0.0.1:8080";  // http://HOST[:PORT] (plain HTTP; put TLS in a proxy)
  std::string token;                             // bearer token; empty: none
  std::chrono::milliseconds connect_timeout{5000};
  std::chrono::milliseconds request_timeout{60000};  // one HTTP exchange (a large upload needs more)
  // Retries, per call. A call is retried after a refused, reset or timed-out connection (only when resending it
  // is safe: GET, DELETE, content-addressed uploads, submissions with their Idempotency-Key), after 429, 502,
  // 503, 504 and 409 "Idempotency-Key in use"; never after any other answer. It gives up with the last error once
  // retry_budget has passed since it began (the last pause is cut short to make one more try at its end), or
  // when a Retry-After does not fit in what is left of it. 0: a single attempt.
  std::chrono::milliseconds retry_budget{60000};
  int max_retries = -1;                             // also at most this many retries; negative: the budget alone
  std::chrono::milliseconds initial_backoff{100};   // first pause without Retry-After, then doubled, each
                                                    // lengthened by up to half at random (jitter)
  std::chrono::milliseconds max_retry_delay{5000};  // cap on the client's own backoff (> 0); a server's
                                                    // Retry-After is waited for as given
  std::string user_agent = "libtexwarp_client/0.1";
};

// How wait() waits: by long-poll (GET /v1/jobs/{id}?wait=S, answered at the job's next change of state or after S
// seconds), S at most kMaxLongPollS and never past the timeout nor beyond half the request timeout. A server that
// answers 400 to ?wait (older than long-poll) is polled instead, every poll_min growing ×1.5 up to poll_max; so is
// any server that answers a long-poll early without a change of state (never a busy loop).
struct WaitOptions {
  std::chrono::milliseconds timeout{0};                      // 0: wait as long as it takes
  std::chrono::milliseconds poll_min{10};                    // polling only: first interval, growing ×1.5 ...
  std::chrono::milliseconds poll_max{500};                   // ... up to this
  std::function<void(const proto::JobStatus&)> on_progress;  // called when state or progress changes
  // With on_progress: the job is asked about at least this often (whole seconds, ≥ 1 s), since a long-poll answers
  // at changes of state only (progress changes within one; a change just before a request arrives shows at the next).
  std::chrono::milliseconds progress_every{1000};
  // Cancels the wait (not the job: cancel() does that): once stop's StopSource is asked to stop (from any thread),
  // wait() returns ErrorCode::kStopped within a few milliseconds, abandoning a request in flight. Default: no stop
  // possible.
  StopToken stop;
};

inline constexpr int kMaxLongPollS = 30;

struct ListOptions {
  std::string cursor;  // next_cursor of the previous page; empty: the newest jobs
  int limit = 50;      // 1–500
  std::optional<proto::JobState> state;
  proto::JobLabels labels;  // only jobs carrying every one of these labels (keys and values as in a job's labels)
};

// Files fetch_results wrote.
struct FetchedFiles {
  std::vector<std::string> paths;  // in the result's order
  proto::JobResult result;
};

class TEXWARP_API Client {
 public:
  explicit Client(ClientOptions options = {});
  ~Client();
  Client(Client&&) noexcept;
  Client& operator=(Client&&) noexcept;
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  const ClientOptions& options() const;

  // POST /v1/blobs: the bytes' content address; use it as {"image": {"blob": id}} (or a mesh source's blob).
  Result<proto::BlobInfo> upload(std::string_view bytes);
  Result<proto::BlobInfo> upload_file(const std::string& path);

  // POST /v1/jobs (the job's priority and labels included). An empty idempotency_key gets a fresh random one, so
  // that the retries of this call are safe.
  Result<proto::JobStatus> submit(const proto::JobSpec& job, const std::string& idempotency_key = {});
  Result<proto::JobStatus> submit_json(const std::string& job_json, const std::string& idempotency_key = {});
  // POST /v1/jobs:batch: 1 to proto::kMaxBatchJobs jobs, accepted all or none; their statuses in the given order.
  // When the server refuses one job, nothing is stored and the error's batch_index (and message) names it. The
  // key (empty: a fresh random one) stands for the whole batch (the server keys each job as "KEY #INDEX").
  Result<std::vector<proto::JobStatus>> submit_batch(const std::vector<proto::JobSpec>& jobs,
                                                     const std::string& idempotency_key = {});

  Result<proto::JobStatus> status(const std::string& job_id);
  // GET /v1/jobs: a page, newest first, filtered by state and labels (kInvalidArgument for a label that no job could
  // carry, before anything is sent).
  Result<proto::JobPage> list(const ListOptions& options = {});
  // Waits (see WaitOptions) until the job is succeeded, failed or canceled and returns that status (a failed job is
  // a successful wait: look at state and error); ErrorCode::kTimeout when options.timeout passes first. A server
  // that goes away meanwhile (a restart) is asked again within retry_budget per request, but never past
  // options.timeout.
  Result<proto::JobStatus> wait(const std::string& job_id, const WaitOptions& options = {});
  // Cancels a queued or running job (POST /v1/jobs/{id}:cancel): its status (canceled, or running with
  // cancel_requested until it stops). kWrongState when the job has already finished, even in the same instant:
  // nothing is changed, its results stay (purge() deletes a finished job).
  Result<proto::JobStatus> cancel(const std::string& job_id);
  // Deletes a finished job's record and result files (DELETE /v1/jobs/{id} → 204); the job is unknown (404)
  // afterwards. kWrongState for a queued or running job (nothing is changed: cancel() stops one).
  Result<bool> purge(const std::string& job_id);
  // GET /v1/nodes: the texwarpd nodes that share the job store, with their heartbeats.
  Result<proto::NodeList> nodes();

  Result<proto::JobResult> result(const std::string& job_id);
  // The succeeded job's report, typed (proto::JobReport: report.schema.json); kProtocol when it does not decode.
  Result<proto::JobReport> report(const std::string& job_id);
  // One result file's bytes, or written to `path` atomically (temporary file, fsync, rename).
  Result<std::string> fetch_file(const std::string& job_id, const std::string& name);
  Result<std::string> fetch_file_to(const std::string& job_id, const std::string& name, const std::string& path);
  // Every result file into `out_dir` (created if missing), each written atomically and checked against its size
  // (the manifest also gives each file's SHA-256).
  Result<FetchedFiles> fetch_results(const std::string& job_id, const std::string& out_dir);

  // submit + wait + fetch_results: kJobFailed / kJobCanceled (with the job's problem) when it does not succeed.
  Result<FetchedFiles> run(const proto::JobSpec& job, const std::string& out_dir, const WaitOptions& wait = {});

  // GET /readyz: the server's readiness document as JSON text (also when it says not ready: its "status").
  Result<std::string> ready();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace texwarp::client
