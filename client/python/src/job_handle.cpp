// JobHandle, ServerJob, LocalJob: see job_handle.hpp.
#include "job_handle.hpp"

#include <unistd.h>

#include <cstdlib>
#include <utility>

#include "texwarp/core/run_control.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/proto/enum_names.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/runner/local_input_resolver.hpp"

namespace texwarp::python {

namespace fs = std::filesystem;

namespace {

nlohmann::json read_report(const fs::path& file) {
  return nlohmann::json::parse(read_text_file(file.string(), 64LL << 20));
}

}  // namespace

std::string JobHandle::state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

double JobHandle::progress() const {
  std::lock_guard lock(mutex_);
  return progress_;
}

bool JobHandle::done() const {
  std::lock_guard lock(mutex_);
  return done_;
}

std::optional<Failure> JobHandle::failure() const {
  std::lock_guard lock(mutex_);
  return failure_;
}

bool JobHandle::wait_for(std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mutex_);
  return changed_.wait_for(lock, timeout, [this] { return done_; });
}

void JobHandle::update(const std::string& state, double progress) {
  std::lock_guard lock(mutex_);
  if (done_) return;
  state_ = state;
  if (progress > progress_) progress_ = progress;  // never backwards, even when a phase starts over
  changed_.notify_all();
}

void JobHandle::finish(const std::string& state, std::optional<Failure> failure) {
  std::lock_guard lock(mutex_);
  state_ = state;
  if (state == "succeeded") progress_ = 1.0;
  done_ = true;
  failure_ = std::move(failure);
  changed_.notify_all();
}

void JobHandle::require_success() const {
  std::lock_guard lock(mutex_);
  if (!done_) throw FailureError(usage_failure("job " + id_ + " has not finished (" + state_ + "): wait() first"));
  if (failure_) throw FailureError(*failure_);
}

// --- ServerJob -------------------------------------------------------------------------------------------------

ServerJob::ServerJob(const client::ClientOptions& options, const std::string& job_json) : control_(options) {
  auto submitted = control_.submit_json(job_json);
  if (!submitted) throw FailureError(failure_from(submitted.error()));
  id_ = submitted->id;
  update(proto::to_string(submitted->state), submitted->progress / 100.0);
  watcher_ = std::thread([this, options] { watch(options); });
}

ServerJob::~ServerJob() {
  stop_.store(true);
  if (watcher_.joinable()) watcher_.join();
}

void ServerJob::watch(client::ClientOptions options) {
  client::Client client(std::move(options));
  client::WaitOptions wait;
  wait.timeout = std::chrono::milliseconds(1000);  // short rounds: stop_ is looked at between them
  wait.on_progress = [this](const proto::JobStatus& s) { update(proto::to_string(s.state), s.progress / 100.0); };
  while (!stop_.load()) {
    auto status = client.wait(id_, wait);
    if (status) {
      update(proto::to_string(status->state), status->progress / 100.0);
      std::optional<Failure> failure;
      if (status->state == proto::JobState::kFailed) {
        Failure f;
        f.kind = Failure::Kind::kJobFailed;
        f.detail = "job " + id_ + " failed";
        if (status->error) {
          f.type = status->error->type;
          f.path = status->error->path;
          f.title = status->error->title;
          f.detail = status->error->detail;
        }
        failure = f;
      } else if (status->state == proto::JobState::kCanceled) {
        failure = Failure{Failure::Kind::kCanceled, "", "", "job " + id_ + " was canceled", "", 0};
      }
      finish(proto::to_string(status->state), failure);
      return;
    }
    if (status.error().code == client::ErrorCode::kTimeout) continue;
    // The server is gone for longer than the retry budget, or answers nonsense: the job cannot be watched.
    finish(state(), failure_from(status.error()));
    return;
  }
}

void ServerJob::cancel() {
  std::lock_guard lock(control_mutex_);
  auto canceled = control_.cancel(id_);
  if (!canceled && canceled.error().code != client::ErrorCode::kWrongState) {
    throw FailureError(failure_from(canceled.error()));
  }
}

JobOutcome ServerJob::fetch(const std::string& out_dir) {
  require_success();
  std::lock_guard lock(control_mutex_);
  auto fetched = control_.fetch_results(id_, out_dir);
  if (!fetched) throw FailureError(failure_from(fetched.error()));
  JobOutcome outcome{id_, state(), fetched->paths, nlohmann::json::object()};
  const fs::path report = fs::path(out_dir) / runner::kReportFile;
  if (fs::exists(report)) outcome.report = read_report(report);
  return outcome;
}

// --- LocalJob --------------------------------------------------------------------------------------------------

LocalJob::LocalJob(const nlohmann::json& job, fs::path base_dir) : base_dir_(std::move(base_dir)) {
  spec_ = proto::decode_job_spec(job);  // InputError with the JSON path
  std::string pattern = (fs::temp_directory_path() / "texwarp-local-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    throw FailureError(usage_failure("cannot make a scratch folder under " + fs::temp_directory_path().string()));
  }
  work_ = pattern;
  id_ = "local:" + work_.filename().string();
  try {
    runner::LocalInputResolver inputs(base_dir_, work_);
    runner::JobLimits limits;
    limits.max_job_memory_bytes = runner::default_job_memory_bytes(1);
    runner::validate_job(spec_, inputs, limits);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(work_, ec);
    throw;
  }
  runner_ = std::thread([this] { run(); });
}

LocalJob::~LocalJob() {
  cancel_.store(true);
  if (runner_.joinable()) runner_.join();
  std::error_code ec;
  fs::remove_all(work_, ec);
}

void LocalJob::run() {
  try {
    update("running", 0.0);
    const fs::path out = work_ / "out";
    fs::create_directories(out);
    runner::LocalInputResolver inputs(base_dir_, work_);
    runner::BackendCache backends;
    runner::JobLimits limits;
    limits.max_job_memory_bytes = runner::default_job_memory_bytes(1);
    RunControl control;
    control.cancel = &cancel_;
    control.progress = [this](double fraction) { update("running", fraction); };
    runner::JobOutput output = runner::run_job(spec_, inputs, backends, out, limits, control);
    files_ = output.files;
    report_ = read_report(out / runner::kReportFile);
    finish("succeeded", std::nullopt);
  } catch (...) {
    Failure f = failure_from_current_exception();
    finish(f.kind == Failure::Kind::kCanceled ? "canceled" : "failed", f);
  }
}

void LocalJob::cancel() { cancel_.store(true); }

JobOutcome LocalJob::fetch(const std::string& out_dir) {
  require_success();
  fs::create_directories(out_dir);
  JobOutcome outcome{id_, "succeeded", {}, report_};
  for (const auto& f : files_) {
    const fs::path to = fs::path(out_dir) / f.name;
    fs::copy_file(work_ / "out" / f.name, to, fs::copy_options::overwrite_existing);
    outcome.files.push_back(to.string());
  }
  return outcome;
}

}  // namespace texwarp::python
