// The job service (submission, queries, workers, recovery): see job_service.hpp.
#include "texwarp/server/job_service.hpp"

#include <malloc.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <fstream>
#include <random>
#include <system_error>

#include "texwarp/core/numerical_error.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/runner/fsync_path.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/server/api_error.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/sha256.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kMinFreeBytes = 64ULL << 20;  // /readyz: the data folder needs this much free space
constexpr std::uint64_t kFullBytes = 1ULL << 20;      // less free than this: a failed write is put down to it
constexpr int kMaxRetryAfterS = 120;
constexpr std::size_t kTrimAfterBodyBytes = 8 << 20;  // a job body this large: heap given back after its parse
constexpr int kStorageRetryAfterS = 30;               // Retry-After of a 507 (the operator has to free space)
constexpr auto kFirstStoreRetry = std::chrono::milliseconds(50);
constexpr auto kLastStoreRetry = std::chrono::milliseconds(2000);

// "job_" + 26 lowercase base32 characters of 128 random bits.
std::string new_job_id() {
  thread_local std::random_device device;
  thread_local std::mt19937_64 rng((static_cast<std::uint64_t>(device()) << 32) ^ device());
  static constexpr char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz234567";
  const std::uint64_t hi = rng() ^ (static_cast<std::uint64_t>(device()) << 32);
  const std::uint64_t lo = rng() ^ device();
  std::string id = "job_";
  for (int i = 0; i < 26; ++i) {
    const int bit = i * 5;
    std::uint64_t v = 0;
    for (int b = 0; b < 5; ++b) {
      const int k = bit + b;
      const std::uint64_t word = k < 64 ? hi : lo;
      v = (v << 1) | ((word >> (63 - (k % 64))) & 1U);
    }
    id.push_back(kAlphabet[v]);
  }
  return id;
}

bool valid_job_id(const std::string& id) {
  if (id.size() != 30 || id.rfind("job_", 0) != 0) return false;
  return std::all_of(id.begin() + 4, id.end(), [](char c) { return (c >= 'a' && c <= 'z') || (c >= '2' && c <= '7'); });
}

ApiError job_not_found(const std::string& id) {
  return ApiError(404, "not-found", "No such job",
                  "there is no job \"" + proto::utf8_prefix(id, 64) + "\" on this server");
}

std::string problem_json(const std::string& slug, const std::string& title, const std::string& detail,
                         const std::string& path = {}) {
  return proto::safe_dump(
      proto::encode_problem({std::string(proto::kProblemTypePrefix) + slug, title, 0, detail, "", path}));
}

std::uint64_t free_bytes_of(const fs::path& folder) {
  struct statvfs vfs {};
  if (::statvfs(folder.c_str(), &vfs) != 0) return 0;
  return static_cast<std::uint64_t>(vfs.f_bavail) * vfs.f_frsize;
}

// A full disk or quota as the store (SQLite), the blob store and std::filesystem report it.
bool is_storage_full(const std::exception& e) {
  const auto* s = dynamic_cast<const std::system_error*>(&e);
  if (s == nullptr) return false;
  const std::error_code& code = s->code();
  const bool errno_code = code.category() == std::generic_category() || code.category() == std::system_category();
  return code == std::errc::no_space_on_device || (errno_code && code.value() == EDQUOT);
}

// 507 for a request the server could not record because its disk is full.
ApiError storage_full(const std::string& what) {
  return ApiError(507, "insufficient-storage", "Insufficient storage",
                  "the server's storage is full, so " + what + "; retry after the time given")
      .retry_after(kStorageRetryAfterS);
}

}  // namespace

JobService::JobService(const ServerConfig& config, JobStore& store, BlobStore& blobs, Metrics& metrics)
    : config_(config),
      store_(store),
      blobs_(blobs),
      metrics_(metrics),
      resolver_(blobs, config.input_roots),
      results_(config.data_dir / "results") {
  fs::create_directories(results_);
}

JobService::~JobService() { shutdown(0.0); }

fs::path JobService::result_dir(const std::string& id) const { return results_ / id; }

void JobService::start() {
  const Recovery r = store_.recover(config_.max_attempts, now_ms());
  // What a previous process left in results/: half-written folders (never served) and folders of jobs the store
  // no longer has (retention deleted the row, then the process died).
  std::size_t orphans = 0;
  for (const auto& entry : fs::directory_iterator(results_)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(".tmp-", 0) == 0 || !valid_job_id(name) || !store_.get(name)) {
      std::error_code ec;
      if (fs::remove_all(entry.path(), ec) > 0) ++orphans;
    }
  }
  for (const auto& id : r.queued) queue_.push(id);
  log_event(LogLevel::kInfo, "recovered jobs",
            {{"queued", r.queued.size()}, {"requeued", r.requeued}, {"canceled", r.canceled}, {"failed", r.failed},
             {"orphaned_results_removed", orphans}, {"blob_temporaries_removed", blobs_.temporaries_removed()}});
  open_default_device();
  for (int i = 0; i < config_.workers; ++i) workers_.emplace_back([this, i] { worker_main(i); });
  if (config_.retention_hours > 0.0) retention_ = std::thread([this] { retention_main(); });
}

void JobService::open_default_device() {
  // Once, before the workers start: OpenCL is initialised on one thread and /readyz tells the device's real state.
  try {
    runner::BackendCache probe(config_.device);
    const WarpBackend& backend = probe.get(std::nullopt, InputLocation::flag("--device"));
    log_event(LogLevel::kInfo, "default device opened", {{"device", probe.default_name()}, {"backend", backend.name()}});
    std::lock_guard lock(device_mutex_);
    device_status_ = "ok";
    device_name_ = backend.name();
  } catch (const std::exception& e) {
    log_event(LogLevel::kError, "default device unavailable", {{"error", e.what()}});
    std::lock_guard lock(device_mutex_);
    device_status_ = std::string("failing: ") + e.what();
  }
}

void JobService::begin_drain() { draining_.store(true); }

void JobService::shutdown(double grace_s) {
  draining_.store(true);
  {
    std::lock_guard lock(stop_mutex_);
    if (stopping_.exchange(true) && workers_.empty()) return;
  }
  stop_cv_.notify_all();
  queue_.close();
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
  for (auto& w : workers_) {
    if (w.joinable()) w.join();
  }
  workers_.clear();
  if (retention_.joinable()) retention_.join();
}

std::shared_ptr<void> JobService::claim_idempotency_key(const std::string& key) {
  std::lock_guard lock(keys_mutex_);
  if (!keys_in_flight_.insert(key).second) {
    throw ApiError(409, "idempotency-key-in-use", "Request with this Idempotency-Key in progress",
                   "another request with this Idempotency-Key is being processed right now; retry after it has "
                   "been answered to get its result")
        .retry_after(1);
  }
  return std::shared_ptr<void>(nullptr, [this, key](void*) {
    std::lock_guard release(keys_mutex_);
    keys_in_flight_.erase(key);
  });
}

// The parse of a large body leaves millions of small freed blocks that glibc keeps resident (a 32 MiB array of
// empty objects: +680 MB for good); trimmed once the parsed value is gone (this guard is destroyed last).
struct TrimHeapAfter {
  bool large = false;
  ~TrimHeapAfter() {
    if (large) ::malloc_trim(0);
  }
};

SubmitResult JobService::submit(const std::string& body, const std::optional<std::string>& idempotency_key) {
  if (draining_.load()) {
    throw ApiError(503, "shutting-down", "Server shutting down", "the server is shutting down; retry shortly")
        .retry_after(5);
  }
  const TrimHeapAfter trim{body.size() >= kTrimAfterBodyBytes};
  nlohmann::json json;
  try {
    json = proto::parse_json(body, "request body");
  } catch (const proto::DuplicateKeyError& e) {  // well-formed JSON whose meaning is ambiguous: an invalid job
    throw ApiError(422, "invalid-job", "Invalid job", e.message_without_file(), e.where().without_file().str());
  } catch (const InputError& e) {
    throw ApiError(400, "malformed-json", "Malformed JSON", e.what());
  }
  proto::JobSpec spec;
  try {
    spec = proto::decode_job_spec(json);
  } catch (const InputError& e) {
    throw ApiError(422, "invalid-job", "Invalid job", e.message_without_file(), e.where().without_file().str());
  }
  const std::string fingerprint = sha256_hex(proto::safe_dump(json));
  const auto replay_or_conflict = [&](const JobRow& existing) {
    if (existing.body_sha256 != fingerprint) {
      throw ApiError(422, "idempotency-key-reused", "Idempotency-Key reused with a different body",
                     "this Idempotency-Key was used for job " + existing.id +
                         " with a different body; use a new key for a new job");
    }
    return SubmitResult{to_status(existing), true};
  };
  if (idempotency_key) {
    if (auto existing = store_.find_by_idempotency_key(*idempotency_key)) return replay_or_conflict(*existing);
  }
  if (queue_.size() >= config_.max_queue) {
    throw ApiError(429, "queue-full", "Queue full",
                   "the server has " + std::to_string(config_.max_queue) + " jobs waiting; retry after the time given")
        .retry_after(retry_after_s());
  }
  try {
    if (spec.image.kind == proto::ImageSourceSpec::Kind::kBase64) {
      const proto::BlobInfo blob = blobs_.put(spec.image.data);
      spec.image.kind = proto::ImageSourceSpec::Kind::kBlob;
      spec.image.blob = blob.id;
      spec.image.data.clear();
    }
    runner::validate_job(spec, resolver_, config_.limits);
  } catch (const InputError& e) {
    throw ApiError(422, "invalid-job", "Invalid job", e.message_without_file(), e.where().without_file().str());
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    log_event(LogLevel::kWarn, "job refused: storage full", {{"error", e.what()}});
    throw storage_full("the job's image could not be stored and the job was not accepted");
  }
  NewJob job;
  job.id = new_job_id();
  job.name = spec.name;
  job.kind = spec.kind();
  job.spec_json = proto::safe_dump(proto::encode_job_spec(spec));
  job.body_sha256 = fingerprint;
  job.idempotency_key = idempotency_key;
  job.created_ms = now_ms();
  std::optional<JobRow> existing;
  try {
    existing = store_.insert(job);
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    log_event(LogLevel::kWarn, "job refused: storage full", {{"error", e.what()}});
    throw storage_full("the job could not be recorded and was not accepted");
  }
  if (existing) return replay_or_conflict(*existing);
  queue_.push(job.id);
  metrics_.job_submitted(proto::to_string(job.kind));
  log_event(LogLevel::kInfo, "job accepted", {{"job", job.id}, {"kind", proto::to_string(job.kind)}, {"name", job.name}});
  const auto row = store_.get(job.id);
  if (!row) throw std::runtime_error("job " + job.id + " vanished after insert");
  return {to_status(*row), false};
}

proto::JobStatus JobService::to_status(const JobRow& row) {
  proto::JobStatus s;
  s.id = row.id;
  s.name = row.name;
  s.kind = row.kind;
  s.state = row.state;
  s.attempts = row.attempts;
  s.cancel_requested = row.cancel_requested;
  s.created_at = rfc3339_utc(row.created_ms);
  if (row.started_ms) s.started_at = rfc3339_utc(*row.started_ms);
  if (row.finished_ms) s.finished_at = rfc3339_utc(*row.finished_ms);
  s.progress = row.state == proto::JobState::kSucceeded ? 100 : row.progress;
  if (row.state == proto::JobState::kRunning) {
    std::lock_guard lock(running_mutex_);
    if (auto it = running_.find(row.id); it != running_.end()) s.progress = it->second->progress.load();
  }
  if (!row.error_json.empty()) s.error = proto::decode_problem(nlohmann::json::parse(row.error_json));
  return s;
}

proto::JobStatus JobService::status(const std::string& id) {
  if (!valid_job_id(id)) throw job_not_found(id);
  const auto row = store_.get(id);
  if (!row) throw job_not_found(id);
  return to_status(*row);
}

proto::JobPage JobService::list(const std::string& cursor, int limit, std::optional<proto::JobState> state) {
  std::optional<std::int64_t> before;
  if (!cursor.empty()) {
    char* end = nullptr;
    const long long seq = std::strtoll(cursor.c_str(), &end, 10);
    if (*end != '\0' || seq <= 0 || cursor.size() > 19) {
      throw ApiError(400, "bad-query", "Bad query parameter",
                     "cursor: not a cursor this server gave out (use next_cursor of the previous page)", "?cursor");
    }
    before = seq;
  }
  const std::vector<JobRow> rows = store_.list(before, limit + 1, state);
  proto::JobPage page;
  for (std::size_t i = 0; i < rows.size() && static_cast<int>(i) < limit; ++i) page.jobs.push_back(to_status(rows[i]));
  if (static_cast<int>(rows.size()) > limit) page.next_cursor = std::to_string(rows[static_cast<std::size_t>(limit) - 1].seq);
  return page;
}

CancelResult JobService::cancel(const std::string& id) {
  if (!valid_job_id(id)) throw job_not_found(id);
  CancelOutcome outcome = CancelOutcome::kNotFound;
  try {
    outcome = store_.request_cancel(id, now_ms());
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    // The store cannot record the request, but a job running here still stops: its end (canceled) is recorded
    // once there is space again.
    std::shared_ptr<RunningJob> job;
    {
      std::lock_guard lock(running_mutex_);
      if (auto it = running_.find(id); it != running_.end()) job = it->second;
    }
    if (!job) throw storage_full("the cancellation could not be recorded");
    job->cancel.store(true);
    log_event(LogLevel::kWarn, "cancellation kept in memory: storage full", {{"job", id}, {"error", e.what()}});
    const auto row = store_.get(id);
    if (!row) throw job_not_found(id);
    CancelResult r{to_status(*row), true};
    r.status.cancel_requested = true;
    return r;
  }
  if (outcome == CancelOutcome::kNotFound) throw job_not_found(id);
  if (outcome == CancelOutcome::kRequested) {
    std::lock_guard lock(running_mutex_);
    if (auto it = running_.find(id); it != running_.end()) it->second->cancel.store(true);
  }
  const auto row = store_.get(id);
  if (!row) throw job_not_found(id);
  if (outcome == CancelOutcome::kAlreadyFinal) {
    throw ApiError(409, "job-finished", "Job already finished",
                   "job " + id + " already " + proto::to_string(row->state) + "; only queued or running jobs can be canceled");
  }
  if (outcome == CancelOutcome::kCanceled) {
    metrics_.job_finished(proto::to_string(row->kind), "canceled", 0.0);
    log_event(LogLevel::kInfo, "job canceled while queued", {{"job", id}});
  }
  return {to_status(*row), outcome == CancelOutcome::kRequested};
}

proto::JobResult JobService::result(const std::string& id) {
  if (!valid_job_id(id)) throw job_not_found(id);
  const auto row = store_.get(id);
  if (!row) throw job_not_found(id);
  if (row->state != proto::JobState::kSucceeded) {
    const std::string state = proto::to_string(row->state);
    throw ApiError(409, "no-result", "Job has no result",
                   "job " + id + " is " + state +
                       (proto::is_terminal(row->state) ? "; only a succeeded job has a result"
                                                       : "; its result is available once it has succeeded (GET /v1/jobs/" + id + ")"));
  }
  proto::JobResult result = proto::decode_job_result(nlohmann::json::parse(row->result_json));
  const fs::path report = result_dir(id) / runner::kReportFile;
  std::ifstream in(report);
  if (!in) throw std::runtime_error("the report of succeeded job " + id + " is missing");
  result.report = nlohmann::json::parse(in);
  return result;
}

fs::path JobService::result_file(const std::string& id, const std::string& name, std::string* media_type,
                                 std::string* sha256) {
  const proto::JobResult r = [&] {
    try {
      return result(id);
    } catch (const ApiError& e) {
      if (e.status() == 409) {
        throw ApiError(404, "not-found", "No such result file", "job " + id + " has no result files: " + e.what());
      }
      throw;
    }
  }();
  for (const auto& f : r.files) {
    if (f.name == name) {
      *media_type = f.media_type;
      *sha256 = f.sha256;
      return result_dir(id) / f.name;
    }
  }
  throw ApiError(404, "not-found", "No such result file",
                 "job " + id + " has no file \"" + name.substr(0, 64) + "\" (GET /v1/jobs/" + id + "/result lists them)");
}

proto::BlobInfo JobService::adopt_blob(const fs::path& temp_file) {
  const proto::BlobInfo info = [&] {
    try {
      return blobs_.adopt(temp_file);
    } catch (const std::exception& e) {
      if (!is_storage_full(e)) throw;
      log_event(LogLevel::kWarn, "blob refused: storage full", {{"error", e.what()}});
      throw storage_full("the blob was not stored");
    }
  }();
  metrics_.blob_uploaded(info.bytes, info.created);
  return info;
}

int JobService::retry_after_s() {
  const double mean = std::max(metrics_.mean_job_seconds(), 0.5);
  const double waiting = static_cast<double>(queue_.size()) - static_cast<double>(config_.max_queue) + 1.0;
  const double s = std::max(1.0, mean * std::max(waiting, 1.0) / config_.workers);
  return static_cast<int>(std::min<double>(std::ceil(s), kMaxRetryAfterS));
}

Readiness JobService::readiness() {
  Readiness r;
  const std::string store = store_.health();
  const bool store_ok = store == "ok";
  std::string device_status;
  std::string device_name;
  {
    std::lock_guard lock(device_mutex_);
    device_status = device_status_;
    device_name = device_name_;
  }
  const std::uint64_t free_bytes = free_bytes_of(config_.data_dir);
  const bool disk_ok = free_bytes >= kMinFreeBytes;
  const bool draining = draining_.load();
  r.ready = store_ok && device_status == "ok" && disk_ok && !draining;
  r.status = r.ready ? "ready" : draining ? "draining" : "not_ready";
  r.checks = {{"store", store},
              {"device", {{"status", device_status}, {"name", device_name}}},
              {"disk", {{"status", disk_ok ? "ok" : "low"}, {"free_bytes", free_bytes}}},
              {"queue", {{"length", queue_.size()}, {"max", config_.max_queue}}},
              {"draining", draining}};
  return r;
}

std::vector<Gauge> JobService::gauges() {
  std::size_t running = 0;
  {
    std::lock_guard lock(running_mutex_);
    running = running_.size();
  }
  return {{"texwarpd_queue_length", "Jobs waiting for a worker.", static_cast<double>(queue_.size())},
          {"texwarpd_queue_capacity", "Queued jobs beyond which submissions get 429.", static_cast<double>(config_.max_queue)},
          {"texwarpd_jobs_running", "Jobs running now.", static_cast<double>(running)},
          {"texwarpd_workers", "Worker threads.", static_cast<double>(config_.workers)},
          {"texwarpd_draining", "1 while shutting down.", draining_.load() ? 1.0 : 0.0}};
}

void JobService::worker_main(int index) {
  std::optional<runner::BackendCache> backends;
  try {
    backends.emplace(config_.device);
    backends->get(std::nullopt, InputLocation::flag("--device"));
  } catch (const std::exception& e) {
    log_event(LogLevel::kError, "default device unavailable", {{"worker", index}, {"error", e.what()}});
    std::lock_guard lock(device_mutex_);
    device_status_ = std::string("failing: ") + e.what();
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

bool JobService::retry_while_full(const std::string& id, const std::function<void()>& write,
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
    std::unique_lock lock(stop_mutex_);
    if (stop_cv_.wait_for(lock, delay, [this] { return stopping_.load(); })) return false;
    lock.unlock();
    delay = std::min<std::chrono::milliseconds>(delay * 2, kLastStoreRetry);
    if (between) between();
  }
}

void JobService::run_one(const std::string& id, runner::BackendCache& backends) {
  bool started = false;
  // While the store is full the job stays queued there; when the server stops first it runs at the next start.
  if (!retry_while_full(id, [&] { started = store_.mark_running(id, now_ms()); })) return;
  if (!started) return;  // canceled while queued
  auto job = std::make_shared<RunningJob>();
  {
    std::lock_guard lock(running_mutex_);
    running_[id] = job;
  }
  struct Unregister {
    JobService& service;
    const std::string& id;
    ~Unregister() {
      std::lock_guard lock(service.running_mutex_);
      service.running_.erase(id);
    }
  } unregister{*this, id};
  const auto start = Clock::now();
  auto row = store_.get(id);
  if (row && row->cancel_requested) job->cancel.store(true);
  const std::string kind = row ? proto::to_string(row->kind) : "image";
  const int attempt = row ? row->attempts : 1;
  log_event(LogLevel::kInfo, "job started", {{"job", id}, {"kind", kind}, {"attempt", attempt}});
  const fs::path temp = results_ / (".tmp-" + id + "-" + std::to_string(attempt));
  std::error_code ec;
  fs::remove_all(temp, ec);

  proto::JobState state = proto::JobState::kFailed;
  std::string error;
  std::string result;
  bool requeue = false;
  try {
    const auto spec_text = store_.spec_json(id);
    if (!spec_text) throw std::runtime_error("the job's spec is missing");
    const proto::JobSpec spec = proto::decode_job_spec(nlohmann::json::parse(*spec_text));
    fs::create_directories(temp);
    RunControl control;
    control.threads = config_.threads_per_job;
    control.cancel = &job->cancel;
    // Progress never goes back (a phase may report from 0 again) and stays below 100 until the result is published.
    control.progress = [job](double f) {
      const int percent = std::clamp(static_cast<int>(f * 100.0), 0, 99);
      int seen = job->progress.load();
      while (percent > seen && !job->progress.compare_exchange_weak(seen, percent)) {
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
    const fs::path final_dir = result_dir(id);
    fs::remove_all(final_dir);
    fs::rename(temp, final_dir);
    runner::fsync_path(results_);
    state = proto::JobState::kSucceeded;
    result = proto::safe_dump(proto::encode_job_result(manifest));
  } catch (const CanceledError&) {
    if (job->shutdown.load()) {
      requeue = true;
    } else {
      state = proto::JobState::kCanceled;
    }
  } catch (const InputError& e) {
    if (!e.where().file_name().empty() && !e.where().json_path()) {  // a file of the server's own, not the job
      log_event(LogLevel::kError, "job failed on a server file", {{"job", id}, {"error", e.what()}});
      error = problem_json("internal", "Internal error",
                           "the job could not be completed because of a server-side error; quote job " + id +
                               " when reporting it");
    } else {
      error = problem_json("invalid-job", "Invalid job", e.message_without_file(), e.where().without_file().str());
    }
  } catch (const NumericalError& e) {
    error = problem_json("numerical-error", "The method could not meet its guarantees", e.what());
  } catch (const std::exception& e) {
    // The result files' writers do not all keep errno: a write that failed on a nearly full disk counts as full.
    if (is_storage_full(e) || free_bytes_of(results_) < kFullBytes) {
      log_event(LogLevel::kWarn, "job failed: storage full", {{"job", id}, {"error", e.what()}});
      error = problem_json("insufficient-storage", "Server storage full",
                           "the server's storage filled up while job " + id +
                               " wrote its results; submit the job again later");
    } else {
      log_event(LogLevel::kError, "job failed with an internal error", {{"job", id}, {"error", e.what()}});
      error = problem_json("internal", "Internal error",
                           "the job could not be completed because of a server-side error; quote job " + id +
                               " when reporting it");
    }
  }
  fs::remove_all(temp, ec);
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  bool counted = false;
  const auto record = [&] {
    if (requeue) {
      store_.requeue(id);
      return;
    }
    if (!counted) metrics_.job_finished(kind, proto::to_string(state), seconds);  // before a client can see it
    counted = true;
    store_.mark_finished(id, state, now_ms(), state == proto::JobState::kSucceeded ? 100 : job->progress.load(), error,
                         result);
  };
  // A cancel request while the end waits for space wins: the job ends canceled and its published result goes.
  const auto cancel_while_waiting = [&] {
    if (requeue || state == proto::JobState::kCanceled || !job->cancel.load()) return;
    state = proto::JobState::kCanceled;
    error.clear();
    result.clear();
    fs::remove_all(result_dir(id), ec);
  };
  if (!retry_while_full(id, record, cancel_while_waiting)) {
    // A cancel kept in memory (the store was full when it came) gets one more try, so that the next start does
    // not run a job its client was told would stop.
    if (job->cancel.load() && !job->shutdown.load()) {
      try {
        store_.request_cancel(id, now_ms());
      } catch (const std::exception& e) {
        log_event(LogLevel::kError, "a cancellation could not be recorded (storage full); the job runs again at the next start",
                  {{"job", id}, {"error", e.what()}});
      }
    }
    log_event(LogLevel::kWarn, "job's end not recorded before shutdown (storage full); it runs again at the next start",
              {{"job", id}});
    return;
  }
  if (!requeue) {
    nlohmann::json fields = {{"job", id}, {"kind", kind}, {"state", proto::to_string(state)}, {"seconds", seconds}};
    if (!error.empty()) fields["error"] = nlohmann::json::parse(error);
    log_event(state == proto::JobState::kFailed ? LogLevel::kWarn : LogLevel::kInfo, "job finished", std::move(fields));
  }
}

void JobService::retention_main() {
  const auto period = std::chrono::duration<double>(std::clamp(config_.retention_hours * 360.0, 1.0, 3600.0));
  std::unique_lock lock(stop_mutex_);
  while (!stopping_.load()) {
    lock.unlock();
    try {
      const auto cutoff = now_ms() - static_cast<std::int64_t>(config_.retention_hours * 3600e3);
      const auto ids = store_.delete_finished_before(cutoff);
      for (const auto& id : ids) {
        std::error_code ec;
        fs::remove_all(result_dir(id), ec);
      }
      if (!ids.empty()) log_event(LogLevel::kInfo, "retention: deleted finished jobs", {{"count", ids.size()}});
    } catch (const std::exception& e) {
      log_event(LogLevel::kError, "retention sweep failed", {{"error", e.what()}});
    }
    lock.lock();
    stop_cv_.wait_for(lock, period, [this] { return stopping_.load(); });
  }
}

}  // namespace texwarp::server
