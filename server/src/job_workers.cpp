// The threads that run jobs: see job_workers.hpp.
#include "texwarp/server/job_workers.hpp"

#include <algorithm>
#include <chrono>

#include "texwarp/core/numerical_error.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/runner/fsync_path.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/server/job_id.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/problem_types.hpp"
#include "texwarp/server/sha256.hpp"
#include "texwarp/server/storage_full.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kFullBytes = 1ULL << 20;  // less free than this: a failed write is put down to it
constexpr auto kFirstStoreRetry = std::chrono::milliseconds(50);
constexpr auto kLastStoreRetry = std::chrono::milliseconds(2000);

std::string job_error_json(ErrorKind kind, const std::string& detail, const std::string& path = {}) {
  return proto::safe_dump(proto::encode_problem(job_problem(kind, detail, path)));
}

std::string internal_error_json(const std::string& id) {
  return job_error_json(ErrorKind::kInternal,
                        "the job could not be completed because of a server-side error; quote job " + id +
                            " when reporting it");
}

}  // namespace

JobWorkers::JobWorkers(const ServerConfig& config, JobStore& store, Metrics& metrics, ServerInputResolver& resolver,
                       JobQueue& queue, const ResultFolders& results, StopSignal& stop)
    : config_(config),
      store_(store),
      metrics_(metrics),
      resolver_(resolver),
      queue_(queue),
      results_(results),
      stop_(stop) {}

void JobWorkers::open_default_device() {
  try {
    runner::BackendCache probe(config_.device);
    const WarpBackend& backend = probe.get(std::nullopt, InputLocation::flag("--device"));
    log_event(LogLevel::kInfo, "default device opened",
              {{"device", probe.default_name()}, {"backend", backend.name()}});
    set_device({"ok", backend.name()});
  } catch (const std::exception& e) {
    log_event(LogLevel::kError, "default device unavailable", {{"error", e.what()}});
    set_device({std::string("failing: ") + e.what(), device().name});
  }
}

void JobWorkers::set_device(DeviceState state) {
  std::lock_guard lock(device_mutex_);
  device_ = std::move(state);
}

DeviceState JobWorkers::device() {
  std::lock_guard lock(device_mutex_);
  return device_;
}

void JobWorkers::start() {
  for (int i = 0; i < config_.workers; ++i) threads_.emplace_back([this, i] { worker_main(i); });
}

void JobWorkers::stop(double grace_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(grace_s);
  for (;;) {
    {
      std::lock_guard lock(running_mutex_);
      if (running_.empty()) break;
      if (Clock::now() >= deadline || grace_cut_.load()) {
        for (auto& [id, job] : running_) {
          job->shutdown.store(true);
          job->cancel.store(true);
          log_event(LogLevel::kInfo, "job interrupted by shutdown; it runs again at the next start", {{"job", id}});
        }
        break;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
  threads_.clear();
}

std::optional<int> JobWorkers::progress(const std::string& id) {
  std::lock_guard lock(running_mutex_);
  if (auto it = running_.find(id); it != running_.end()) return it->second->progress.load();
  return std::nullopt;
}

bool JobWorkers::cancel_running(const std::string& id) {
  std::lock_guard lock(running_mutex_);
  auto it = running_.find(id);
  if (it == running_.end()) return false;
  it->second->cancel.store(true);
  return true;
}

Cancellation JobWorkers::cancel(const std::string& id) {
  if (!is_job_id(id)) throw job_not_found(id);
  CancelOutcome outcome = CancelOutcome::kNotFound;
  try {
    outcome = store_.request_cancel(id, now_ms());
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    // The store cannot record the request, but a job running here still stops: its end (canceled) is recorded
    // once there is space again.
    if (!cancel_running(id)) throw storage_full_error("the cancellation could not be recorded");
    log_event(LogLevel::kWarn, "cancellation kept in memory: storage full", {{"job", id}, {"error", e.what()}});
    auto row = store_.get(id);
    if (!row) throw job_not_found(id);
    row->cancel_requested = true;
    return {std::move(*row), true};
  }
  if (outcome == CancelOutcome::kNotFound) throw job_not_found(id);
  if (outcome == CancelOutcome::kRequested) cancel_running(id);
  auto row = store_.get(id);
  if (!row) throw job_not_found(id);
  if (outcome == CancelOutcome::kAlreadyFinal) {
    throw ServiceError(ErrorKind::kJobFinished, "job " + id + " already " + proto::to_string(row->state) +
                                                    "; only queued or running jobs can be canceled");
  }
  if (outcome == CancelOutcome::kCanceled) {
    metrics_.job_finished(proto::to_string(row->kind), "canceled", 0.0);
    log_event(LogLevel::kInfo, "job canceled while queued", {{"job", id}});
  }
  return {std::move(*row), outcome == CancelOutcome::kRequested};
}

std::size_t JobWorkers::running_count() {
  std::lock_guard lock(running_mutex_);
  return running_.size();
}

void JobWorkers::worker_main(int index) {
  std::optional<runner::BackendCache> backends;
  try {
    backends.emplace(config_.device);
    backends->get(std::nullopt, InputLocation::flag("--device"));
  } catch (const std::exception& e) {
    log_event(LogLevel::kError, "default device unavailable", {{"worker", index}, {"error", e.what()}});
    set_device({std::string("failing: ") + e.what(), device().name});
    if (!backends) return;
  }
  while (auto id = queue_.pop()) {
    try {
      run_one(*id, *backends);
    } catch (const std::exception& e) {
      // The store failed otherwise than full (an I/O error): the job stays as it was and runs again after a restart.
      log_event(LogLevel::kError, "worker could not record a job", {{"job", *id}, {"error", e.what()}});
    }
  }
}

bool JobWorkers::retry_while_full(const std::string& id, const std::function<void()>& write,
                                  const std::function<void()>& between) {
  auto delay = kFirstStoreRetry;
  bool waited = false;
  for (;;) {
    try {
      write();
      if (waited) log_event(LogLevel::kInfo, "the store takes writes again", {{"job", id}});
      return true;
    } catch (const std::exception& e) {
      if (!is_storage_full(e)) throw;
      if (!waited) {
        log_event(LogLevel::kWarn, "the store is full: the job's state is written once there is space",
                  {{"job", id}, {"error", e.what()}});
      }
      waited = true;
    }
    if (stop_.wait_for(delay)) return false;
    delay = std::min<std::chrono::milliseconds>(delay * 2, kLastStoreRetry);
    if (between) between();
  }
}

std::shared_ptr<JobWorkers::RunningJob> JobWorkers::register_running(const std::string& id) {
  auto job = std::make_shared<RunningJob>();
  std::lock_guard lock(running_mutex_);
  running_[id] = job;
  return job;
}

void JobWorkers::unregister_running(const std::string& id) {
  std::lock_guard lock(running_mutex_);
  running_.erase(id);
}

void JobWorkers::run_one(const std::string& id, runner::BackendCache& backends) {
  bool started = false;
  // While the store is full the job stays queued there; when the server stops first it runs at the next start.
  if (!retry_while_full(id, [&] { started = store_.mark_running(id, now_ms()); })) return;
  if (!started) return;  // canceled while queued
  const auto job = register_running(id);
  struct Unregister {
    JobWorkers& workers;
    const std::string& id;
    ~Unregister() { workers.unregister_running(id); }
  } unregister{*this, id};
  const auto start = Clock::now();
  const auto row = store_.get(id);
  if (row && row->cancel_requested) job->cancel.store(true);
  const std::string kind = row ? proto::to_string(row->kind) : "image";
  const int attempt = row ? row->attempts : 1;
  log_event(LogLevel::kInfo, "job started", {{"job", id}, {"kind", kind}, {"attempt", attempt}});
  Outcome outcome = execute(id, attempt, *job, backends);
  record(id, kind, *job, outcome, std::chrono::duration<double>(Clock::now() - start).count());
}

JobWorkers::Outcome JobWorkers::execute(const std::string& id, int attempt, RunningJob& job,
                                        runner::BackendCache& backends) {
  const fs::path temp = results_.temporary(id, attempt);
  std::error_code ec;
  fs::remove_all(temp, ec);
  Outcome out;
  try {
    out.result = run_and_publish(id, temp, job, backends);
    out.state = proto::JobState::kSucceeded;
  } catch (const CanceledError&) {
    if (job.shutdown.load()) {
      out.requeue = true;
    } else {
      out.state = proto::JobState::kCanceled;
    }
  } catch (const InputError& e) {
    if (!e.where().file_name().empty() && !e.where().json_path()) {  // a file of the server's own, not the job
      log_event(LogLevel::kError, "job failed on a server file", {{"job", id}, {"error", e.what()}});
      out.error = internal_error_json(id);
    } else {
      out.error = job_error_json(ErrorKind::kInvalidJob, e.message_without_file(), e.where().without_file().str());
    }
  } catch (const NumericalError& e) {
    out.error = job_error_json(ErrorKind::kNumericalError, e.what());
  } catch (const std::exception& e) {
    // The result files' writers do not all keep errno: a write that failed on a nearly full disk counts as full.
    if (is_storage_full(e) || free_bytes_of(results_.root()) < kFullBytes) {
      log_event(LogLevel::kWarn, "job failed: storage full", {{"job", id}, {"error", e.what()}});
      out.error = job_error_json(ErrorKind::kStorageFull, "the server's storage filled up while job " + id +
                                                              " wrote its results; submit the job again later");
    } else {
      log_event(LogLevel::kError, "job failed with an internal error", {{"job", id}, {"error", e.what()}});
      out.error = internal_error_json(id);
    }
  }
  fs::remove_all(temp, ec);
  return out;
}

std::string JobWorkers::run_and_publish(const std::string& id, const fs::path& temp, RunningJob& job,
                                        runner::BackendCache& backends) {
  const auto spec_text = store_.spec_json(id);
  if (!spec_text) throw std::runtime_error("the job's spec is missing");
  const proto::JobSpec spec = proto::decode_job_spec(nlohmann::json::parse(*spec_text));
  fs::create_directories(temp);
  RunControl control;
  control.threads = config_.threads_per_job;
  control.cancel = &job.cancel;
  // Progress never goes back (a phase may report from 0 again) and stays below 100 until the result is published.
  control.progress = [&job](double f) {
    const int percent = std::clamp(static_cast<int>(f * 100.0), 0, 99);
    int seen = job.progress.load();
    while (percent > seen && !job.progress.compare_exchange_weak(seen, percent)) {
    }
  };
  const runner::JobOutput out = runner::run_job(spec, resolver_, backends, temp, config_.limits, control);
  proto::JobResult manifest;
  manifest.job_id = id;
  manifest.kind = spec.kind();
  for (const auto& f : out.files) {
    proto::ResultFile file;
    file.name = f.name;
    file.media_type = f.media_type;
    file.sha256 = sha256_file_hex(temp / f.name, &file.bytes);
    file.href = "/v1/jobs/" + id + "/files/" + f.name;
    manifest.files.push_back(std::move(file));
  }
  manifest.report = nlohmann::json::object();  // served from report.json
  runner::fsync_path(temp);
  const fs::path final_dir = results_.published(id);
  fs::remove_all(final_dir);
  fs::rename(temp, final_dir);
  runner::fsync_path(results_.root());
  return proto::safe_dump(proto::encode_job_result(manifest));
}

void JobWorkers::record(const std::string& id, const std::string& kind, RunningJob& job, Outcome& outcome,
                        double seconds) {
  bool counted = false;
  const auto write = [&] {
    if (outcome.requeue) {
      store_.requeue(id);
      return;
    }
    if (!counted) metrics_.job_finished(kind, proto::to_string(outcome.state), seconds);  // before a client sees it
    counted = true;
    store_.mark_finished(id, outcome.state, now_ms(),
                         outcome.state == proto::JobState::kSucceeded ? 100 : job.progress.load(), outcome.error,
                         outcome.result);
  };
  // A cancel request while the end waits for space wins: the job ends canceled and its published result goes.
  const auto cancel_while_waiting = [&] {
    if (outcome.requeue || outcome.state == proto::JobState::kCanceled || !job.cancel.load()) return;
    outcome.state = proto::JobState::kCanceled;
    outcome.error.clear();
    outcome.result.clear();
    std::error_code ec;
    fs::remove_all(results_.published(id), ec);
  };
  if (!retry_while_full(id, write, cancel_while_waiting)) {
    // A cancel kept in memory (the store was full when it came) gets one more try, so that the next start does
    // not run a job its client was told would stop.
    if (job.cancel.load() && !job.shutdown.load()) {
      try {
        store_.request_cancel(id, now_ms());
      } catch (const std::exception& e) {
        log_event(LogLevel::kError,
                  "a cancellation could not be recorded (storage full); the job runs again at the next start",
                  {{"job", id}, {"error", e.what()}});
      }
    }
    log_event(LogLevel::kWarn, "job's end not recorded before shutdown (storage full); it runs again at the next start",
              {{"job", id}});
    return;
  }
  if (outcome.requeue) return;
  nlohmann::json fields = {{"job", id},
                           {"kind", kind},
                           {"state", proto::to_string(outcome.state)},
                           {"seconds", seconds}};
  if (!outcome.error.empty()) fields["error"] = nlohmann::json::parse(outcome.error);
  log_event(outcome.state == proto::JobState::kFailed ? LogLevel::kWarn : LogLevel::kInfo, "job finished",
            std::move(fields));
}

}  // namespace texwarp::server
