// JobHandle: a job running on a texwarpd (ServerJob, watched by a background thread through the client library) or
// in this process (LocalJob, the runner on a background thread), seen the same way: state and progress read
// without blocking (a DCC's main loop), a blocking wait, cancel, fetch of the result files. No Python in here.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "python_failure.hpp"
#include "texwarp/client/client.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/runner/job_runner.hpp"

namespace texwarp::python {

// What fetch() gives: the files written into the folder and the job's report (report.json).
// NOLINTNEXTLINE(bugprone-exception-escape): its implicit moves are noexcept; clang-tidy 14 says nlohmann::json's throw
struct JobOutcome {
  std::string job_id;
  std::string state;
  std::vector<std::string> files;  // paths, in the result's order
  nlohmann::json report;
};

class JobHandle {
 public:
  virtual ~JobHandle() = default;

  const std::string& id() const { return id_; }
  std::string state() const;               // "queued", "running", "succeeded", "failed", "canceled"
  double progress() const;                 // 0..1
  bool done() const;                       // the job ended (or could no longer be watched: see failure())
  std::optional<Failure> failure() const;  // why it did not succeed, once done

  // Waits up to `timeout` for the job to end; true when it has.
  bool wait_for(std::chrono::milliseconds timeout) const;
  // Asks the job to stop (a finished job is left as it is); the state turns "canceled" once it has stopped.
  virtual void cancel() = 0;
  // The result files into `out_dir` (created if missing) and the report; FailureError when the job has not
  // finished (kUsage), failed (kJobFailed) or was canceled.
  virtual JobOutcome fetch(const std::string& out_dir) = 0;

 protected:
  void update(const std::string& state, double progress);
  void finish(const std::string& state, std::optional<Failure> failure);
  // FailureError unless the job succeeded.
  void require_success() const;

  std::string id_;

 private:
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::string state_ = "queued";
  double progress_ = 0.0;
  bool done_ = false;
  std::optional<Failure> failure_;
};

// A job submitted to a texwarpd. FailureError from the constructor when the server refuses it (the problem's path).
class ServerJob final : public JobHandle {
 public:
  ServerJob(const client::ClientOptions& options, const std::string& job_json);
  ~ServerJob() override;
  void cancel() override;
  JobOutcome fetch(const std::string& out_dir) override;

 private:
  void watch(client::ClientOptions options);

  std::mutex control_mutex_;
  client::Client control_;  // cancel and fetch, from the caller's thread (one call at a time)
  std::atomic<bool> stop_{false};
  std::thread watcher_;
};

// A job run in this process through the runner (the `texwarp run` path): paths relative to `base_dir`, inline
// images, no blobs. The job is decoded and planned (validate_job) in the constructor: FailureError (kInput, with
// the JSON path) for a job that is wrong; the run itself goes on a background thread.
class LocalJob final : public JobHandle {
 public:
  LocalJob(const nlohmann::json& job, std::filesystem::path base_dir);
  ~LocalJob() override;
  void cancel() override;
  JobOutcome fetch(const std::string& out_dir) override;

 private:
  void run();

  proto::JobSpec spec_;
  std::filesystem::path base_dir_;
  std::filesystem::path work_;  // the run's own folder (removed with the job)
  std::atomic<bool> cancel_{false};
  std::vector<runner::JobFile> files_;
  nlohmann::json report_;
  std::thread runner_;
};

}  // namespace texwarp::python
