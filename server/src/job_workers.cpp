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
#include "texwarp/proto/problem_details_codec.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/runner/fsync_path.hpp"
#include "texwarp/runner/job_runner.hpp"
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

std::int64_t lease_ms(const ServerConfig& config) { return static_cast<std::int64_t>(config.lease_s * 1000.0); }

// Why a store write cannot be done now but may later: a full disk or a store that cannot be reached.
bool is_transient(const std::exception& e) {
  return dynamic_cast<const StoreUnavailable*>(&e) != nullptr || is_storage_full(e);
}

}  // namespace

JobWorkers::JobWorkers(const ServerConfig& config, JobStore& store, Metrics& metrics, ServerInputResolver& resolver,
                       WorkSignal& work, JobWatchers& watchers, const ResultFolders& results, StopSignal& stop)
    : config_(config),
      store_(store),
      metrics_(metrics),
      resolver_(resolver),
      work_(work),
      watchers_(watchers),
      results_(results),
      stop_(stop) {}

void JobWorkers::open_default_device() {
  try {
    if (!config_.cache_dir.empty()) runner::use_kernel_cache_dir(config_.cache_dir.string());
    runner::BackendCache probe(config_.device);
    const WarpBackend& backend = probe.get(std::nullopt, InputLocation::flag("--device"));
    // Every kernel variant is built and launched once now (compiled into the cache folder, or found there),
    // before /readyz says ready: no job pays for it.
    const std::string kernels = runner::warm_kernels(config_.device ? *config_.device : proto::DeviceSpec::opencl());
    log_event(LogLevel::kInfo, "default device opened",
              {{"device", probe.default_name()}, {"backend", backend.name()}, {"kernels", kernels}});
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

void JobWorkers::start(const std::string& node_id) {
  node_id_ = node_id;
  started_.store(true);
  starter_ = std::thread([this] {
    open_default_device();
    if (stop_.is_set()) return;  // stopped while the kernels were built: no worker to start
    for (int i = 0; i < config_.workers; ++i) threads_.emplace_back([this, i] { worker_main(i); });
  });
}

void JobWorkers::stop(double grace_s) {
  work_.close();
  // A start still building kernels finishes that first (OpenCL's build is not interruptible), then sees the stop.
  if (starter_.joinable()) starter_.join();
  const auto deadline = Clock::now() + std::chrono::duration<double>(grace_s);
  for (;;) {
    {
      std::lock_guard lock(running_mutex_);
      const bool over = running_.empty() || Clock::now() >= deadline || grace_cut_.load();
      if (over) {
        // From now on, a job still running or claimed by a worker that was mid-claim is stopped and released.
        interrupt_new_ = true;
        for (auto& [id, job] : running_) {
          job->shutdown.store(true);
          job->cancel.store(true);
          log_event(LogLevel::kInfo, "job interrupted by shutdown; it is queued again", {{"job", id}});
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

std::vector<HeldLease> JobWorkers::held_leases() {
  std::vector<HeldLease> out;
  std::lock_guard lock(running_mutex_);
  for (const auto& [id, job] : running_) out.push_back({id, job->epoch, job->progress.load()});
  return out;
}

void JobWorkers::renewed(const std::string& id, std::int64_t epoch, const Renewal& renewal) {
  std::lock_guard lock(running_mutex_);
  const auto it = running_.find(id);
  if (it == running_.end() || it->second->epoch != epoch) return;
  if (!renewal.held) {
    if (!it->second->lost.exchange(true)) {
      metrics_.lease_lost();
      log_event(LogLevel::kWarn, "lease_lost",
                {{"job", id},
                 {"epoch", epoch},
                 {"node", node_id_},
                 {"detail", "the job's lease expired and was reclaimed; the run stops here and records nothing"}});
    }
    it->second->cancel.store(true);
  } else if (renewal.cancel_requested) {
    it->second->cancel.store(true);
  }
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

std::size_t JobWorkers::running_count() {
  std::lock_guard lock(running_mutex_);
  return running_.size();
}

std::optional<Lease> JobWorkers::claim_next(std::chrono::milliseconds& backoff) {
  try {
    auto lease = store_.claim(node_id_, now_ms(), lease_ms(config_));
    if (backoff > std::chrono::milliseconds(0)) log_event(LogLevel::kInfo, "the store answers claims again");
    backoff = std::chrono::milliseconds(0);
    if (!lease) work_.wait_for(std::chrono::milliseconds(config_.poll_ms));
    return lease;
  } catch (const std::exception& e) {
    if (backoff == std::chrono::milliseconds(0)) {
      log_event(is_transient(e) ? LogLevel::kWarn : LogLevel::kError, "cannot claim jobs; retrying",
                {{"node", node_id_}, {"error", e.what()}});
    }
    backoff = std::clamp<std::chrono::milliseconds>(backoff * 2, kFirstStoreRetry, kLastStoreRetry);
    stop_.wait_for(backoff);
    return std::nullopt;
  }
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
  std::chrono::milliseconds backoff(0);
  while (!stop_.is_set()) {
    const auto lease = claim_next(backoff);
    if (!lease) continue;
    try {
      run_one(*lease, *backends);
    } catch (const std::exception& e) {
      // The store failed otherwise than full or unreachable: the job stays as it was; its lease expires and it is
      // reclaimed.
      log_event(LogLevel::kError, "worker could not record a job", {{"job", lease->job_id}, {"error", e.what()}});
    }
  }
}

bool JobWorkers::retry_store(const std::string& id, const std::function<void()>& write,
                             const std::function<bool()>& between) {
  auto delay = kFirstStoreRetry;
  bool waited = false;
  for (;;) {
    try {
      write();
      if (waited) log_event(LogLevel::kInfo, "the store takes writes again", {{"job", id}});
      return true;
    } catch (const std::exception& e) {
      if (!is_transient(e)) throw;
      if (!waited) {
        log_event(LogLevel::kWarn,
                  is_storage_full(e) ? "the store is full: the job's state is written once there is space"
                                     : "the store cannot be reached: the job's state is written once it answers",
                  {{"job", id}, {"error", e.what()}});
      }
      waited = true;
    }
    if (stop_.wait_for(delay)) return false;
    delay = std::min<std::chrono::milliseconds>(delay * 2, kLastStoreRetry);
    if (between && !between()) return false;
  }
}

std::shared_ptr<JobWorkers::RunningJob> JobWorkers::register_running(const std::string& id, std::int64_t epoch) {
  auto job = std::make_shared<RunningJob>();
  job->epoch = epoch;
  std::lock_guard lock(running_mutex_);
  if (interrupt_new_) {
    job->shutdown.store(true);
    job->cancel.store(true);
  }
  running_[id] = job;
  return job;
}

void JobWorkers::unregister_running(const std::string& id, const RunningJob* job) {
  std::lock_guard lock(running_mutex_);
  // Only this run's own entry: a run that lost its lease may end after the same job's next run (its next epoch, on
  // another worker of this node) registered, whose lease would then never be renewed again.
  if (const auto it = running_.find(id); it != running_.end() && it->second.get() == job) running_.erase(it);
}

void JobWorkers::run_one(const Lease& lease, runner::BackendCache& backends) {
  const std::string& id = lease.job_id;
  const auto job = register_running(id, lease.epoch);
  struct Unregister {
    JobWorkers& workers;
    const std::string& id;
    const RunningJob* job;
    ~Unregister() { workers.unregister_running(id, job); }
  } unregister{*this, id, job.get()};
  watchers_.changed(id);
  const auto start = Clock::now();
  std::optional<proto::JobSpec> spec;
  Outcome outcome;
  try {
    spec = proto::decode_job_spec(nlohmann::json::parse(lease.spec_json));
  } catch (const std::exception& e) {
    log_event(LogLevel::kError, "a claimed job's stored spec does not decode", {{"job", id}, {"error", e.what()}});
    outcome.error = internal_error_json(id);
  }
  const std::string kind = spec ? proto::to_string(spec->kind()) : "image";
  log_event(LogLevel::kInfo, "job started",
            {{"job", id}, {"kind", kind}, {"attempt", lease.attempt}, {"epoch", lease.epoch}, {"node", node_id_}});
  if (spec) outcome = execute(lease, *spec, *job, backends);
  record(lease, kind, *job, outcome, std::chrono::duration<double>(Clock::now() - start).count());
}

JobWorkers::Outcome JobWorkers::execute(const Lease& lease, const proto::JobSpec& spec, RunningJob& job,
                                        runner::BackendCache& backends) {
  const std::string& id = lease.job_id;
  const fs::path temp = results_.temporary(id, lease.epoch);
  std::error_code ec;
  fs::remove_all(temp, ec);
  Outcome out;
  try {
    out.result = run_and_publish(lease, spec, job, backends, &out.result_folder);
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
  out.lost = job.lost.load();
  return out;
}

std::string JobWorkers::run_and_publish(const Lease& lease, const proto::JobSpec& spec, RunningJob& job,
                                        runner::BackendCache& backends, std::string* folder) {
  const std::string& id = lease.job_id;
  const fs::path temp = results_.temporary(id, lease.epoch);
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
    file.role = f.role;
    manifest.files.push_back(std::move(file));
  }
  manifest.report_json = "{}";  // served from report.json
  runner::fsync_path(temp);
  if (job.lost.load()) throw CanceledError();  // the lease was lost: nothing is published
  const std::string name = ResultFolders::published_name(id, lease.epoch);
  const fs::path final_dir = results_.folder(name);
  // Never over another folder: an epoch is claimed once, so a folder of this name is a bug, not a retry.
  if (fs::exists(final_dir)) throw std::runtime_error("result folder " + final_dir.string() + " exists already");
  fs::rename(temp, final_dir);
  runner::fsync_path(results_.root());
  *folder = name;
  return proto::safe_dump(proto::encode_job_result(manifest));
}

void JobWorkers::record(const Lease& lease, const std::string& kind, RunningJob& job, Outcome& outcome,
                        double seconds) {
  const std::string& id = lease.job_id;
  // The folder this run published (`<id>.<epoch>`: no other run names it), empty when it published none.
  const std::string published = outcome.result_folder;
  const auto remove_published = [&] {
    outcome.result_folder.clear();
    if (published.empty()) return;
    std::error_code ec;
    fs::remove_all(results_.folder(published), ec);
  };
  // A write whose reply was lost (the connection broke after the store committed it) is retried, and the retry is
  // fenced (the job is no longer running), or the heartbeat then finds the lease gone: the job's row already holds
  // this run's end, and names its folder. Before a fenced or lost run's folder goes, the row is read: the folder
  // stays when the row names it (the run's end is recorded); when the row cannot be read it stays too, since an
  // orphan folder loses nothing and a removed one that a succeeded job names loses its result.
  const auto recorded_by_a_lost_reply = [&] {
    if (published.empty()) return false;
    try {
      const std::optional<JobRow> row = store_.get(id);
      return row && row->result_folder == published;
    } catch (const std::exception& e) {
      log_event(LogLevel::kWarn, "job's end uncertain: the store could not be read; its result folder is kept",
                {{"job", id}, {"folder", published}, {"error", e.what()}});
      return true;
    }
  };
  const auto end_recorded_earlier = [&] {
    log_event(LogLevel::kInfo, "job finished: its end was recorded by a write whose reply was lost",
              {{"job", id}, {"epoch", lease.epoch}, {"folder", published}});
    watchers_.changed(id);
  };
  if (outcome.lost) {
    remove_published();
    log_event(LogLevel::kWarn, "job stopped: its lease was lost (another node may run it); nothing recorded",
              {{"job", id}, {"epoch", lease.epoch}});
    return;
  }
  bool counted = false;
  bool fenced = false;
  const auto write = [&] {
    if (outcome.requeue) {
      fenced = !store_.release(id, lease.epoch);
      return;
    }
    if (!counted) metrics_.job_finished(kind, proto::to_string(outcome.state), seconds);  // before a client sees it
    counted = true;
    fenced = !store_.finish(id, lease.epoch, outcome.state, now_ms(),
                            outcome.state == proto::JobState::kSucceeded ? 100 : job.progress.load(), outcome.error,
                            outcome.result, outcome.result_folder);
  };
  // While the end waits for the store: a lost lease ends the wait (nothing may be recorded), and a cancel request
  // wins (the job ends canceled and its published result goes).
  const auto between = [&] {
    if (job.lost.load()) return false;
    if (outcome.requeue || outcome.state == proto::JobState::kCanceled || !job.cancel.load()) return true;
    outcome.state = proto::JobState::kCanceled;
    outcome.error.clear();
    outcome.result.clear();
    outcome.result_folder.clear();  // the folder goes once the cancel is recorded (an earlier write may name it)
    return true;
  };
  if (!retry_store(id, write, between)) {
    if (job.lost.load() && recorded_by_a_lost_reply()) {
      end_recorded_earlier();
      return;
    }
    if (job.lost.load()) {
      remove_published();
      log_event(LogLevel::kWarn, "job stopped: its lease was lost while its end waited for the store",
                {{"job", id}, {"epoch", lease.epoch}});
      return;
    }
    log_event(LogLevel::kWarn,
              "job's end not recorded before shutdown (the store could not take it); its lease expires and it runs "
              "again",
              {{"job", id}});
    return;
  }
  if (fenced && !outcome.requeue && recorded_by_a_lost_reply()) {
    end_recorded_earlier();
    return;
  }
  if (fenced) {
    remove_published();
    if (!outcome.requeue) metrics_.job_fenced();
    log_event(LogLevel::kWarn, "job_fenced",
              {{"job", id},
               {"epoch", lease.epoch},
               {"node", node_id_},
               {"detail", "another node holds the job's lease now; this run's outcome was discarded"}});
    return;
  }
  if (outcome.result_folder.empty()) remove_published();  // a cancel that won while the end waited for the store
  watchers_.changed(id);
  if (outcome.requeue) {
    work_.notify();
    return;
  }
  nlohmann::json fields = {{"job", id},
                           {"kind", kind},
                           {"state", proto::to_string(outcome.state)},
                           {"seconds", seconds},
                           {"epoch", lease.epoch}};
  if (!outcome.error.empty()) fields["error"] = nlohmann::json::parse(outcome.error);
  log_event(outcome.state == proto::JobState::kFailed ? LogLevel::kWarn : LogLevel::kInfo, "job finished",
            std::move(fields));
}

}  // namespace texwarp::server
