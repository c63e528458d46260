// The service as the routes see it (start-up, shutdown, reads): see job_service.hpp.
#include "texwarp/server/job_service.hpp"

#include <cstdlib>
#include <fstream>

#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/server/job_id.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/service_error.hpp"
#include "texwarp/server/storage_full.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kMinFreeBytes = 64ULL << 20;  // /readyz: the data folder needs this much free space

}  // namespace

JobService::JobService(const ServerConfig& config, JobStore& store, BlobStore& blobs, Metrics& metrics)
    : config_(config),
      store_(store),
      blobs_(blobs),
      metrics_(metrics),
      resolver_(blobs, config.input_roots),
      results_(config.data_dir),
      admission_(config, store, blobs, metrics, resolver_, queue_),
      workers_(config, store, metrics, resolver_, queue_, results_, stop_),
      retention_(config, store, results_, stop_) {}

JobService::~JobService() { shutdown(0.0); }

void JobService::start() {
  const Recovery r = store_.recover(config_.max_attempts, now_ms());
  const std::size_t orphans = retention_.remove_orphans();
  for (const auto& id : r.queued) queue_.push(id);
  log_event(LogLevel::kInfo, "recovered jobs",
            {{"queued", r.queued.size()},
             {"requeued", r.requeued},
             {"canceled", r.canceled},
             {"failed", r.failed},
             {"orphaned_results_removed", orphans},
             {"blob_temporaries_removed", blobs_.temporaries_removed()}});
  workers_.open_default_device();
  workers_.start();
  retention_.start();
}

void JobService::shutdown(double grace_s) {
  admission_.begin_drain();
  if (stop_.set() && !workers_.started()) return;
  queue_.close();
  workers_.stop(grace_s);
  retention_.join();
}

SubmitResult JobService::submit(const std::string& body, const std::optional<std::string>& idempotency_key) {
  const Admitted admitted = admission_.submit(body, idempotency_key);
  return {to_status(admitted.row), admitted.replayed};
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
    if (const auto running = workers_.progress(row.id)) s.progress = *running;
  }
  if (!row.error_json.empty()) s.error = proto::decode_problem(nlohmann::json::parse(row.error_json));
  return s;
}

proto::JobStatus JobService::status(const std::string& id) {
  if (!is_job_id(id)) throw job_not_found(id);
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
      throw ServiceError(ErrorKind::kBadQuery,
                         "cursor: not a cursor this server gave out (use next_cursor of the previous page)", "?cursor");
    }
    before = seq;
  }
  const std::vector<JobRow> rows = store_.list(before, limit + 1, state);
  proto::JobPage page;
  for (std::size_t i = 0; i < rows.size() && static_cast<int>(i) < limit; ++i) page.jobs.push_back(to_status(rows[i]));
  if (static_cast<int>(rows.size()) > limit)
    page.next_cursor = std::to_string(rows[static_cast<std::size_t>(limit) - 1].seq);
  return page;
}

CancelResult JobService::cancel(const std::string& id) {
  const Cancellation c = workers_.cancel(id);
  return {to_status(c.row), c.requested};
}

proto::JobResult JobService::result(const std::string& id) {
  if (!is_job_id(id)) throw job_not_found(id);
  const auto row = store_.get(id);
  if (!row) throw job_not_found(id);
  if (row->state != proto::JobState::kSucceeded) {
    const std::string state = proto::to_string(row->state);
    throw ServiceError(ErrorKind::kNoResult,
                       "job " + id + " is " + state +
                           (proto::is_terminal(row->state)
                                ? "; only a succeeded job has a result"
                                : "; its result is available once it has succeeded (GET /v1/jobs/" + id + ")"));
  }
  proto::JobResult result = proto::decode_job_result(nlohmann::json::parse(row->result_json));
  const fs::path report = results_.published(id) / runner::kReportFile;
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
    } catch (const ServiceError& e) {
      if (e.kind() == ErrorKind::kNoResult) {
        throw ServiceError(ErrorKind::kNotFound, "job " + id + " has no result files: " + e.detail());
      }
      throw;
    }
  }();
  for (const auto& f : r.files) {
    if (f.name == name) {
      *media_type = f.media_type;
      *sha256 = f.sha256;
      return results_.published(id) / f.name;
    }
  }
  throw ServiceError(ErrorKind::kNotFound, "job " + id + " has no file \"" + name.substr(0, 64) + "\" (GET /v1/jobs/" +
                                               id + "/result lists them)");
}

proto::BlobInfo JobService::adopt_blob(const fs::path& temp_file) {
  const proto::BlobInfo info = [&] {
    try {
      return blobs_.adopt(temp_file);
    } catch (const std::exception& e) {
      if (!is_storage_full(e)) throw;
      log_event(LogLevel::kWarn, "blob refused: storage full", {{"error", e.what()}});
      throw storage_full_error("the blob was not stored");
    }
  }();
  metrics_.blob_uploaded(info.bytes, info.created);
  return info;
}

Readiness JobService::readiness() {
  Readiness r;
  const std::string store = store_.health();
  const bool store_ok = store == "ok";
  const DeviceState device = workers_.device();
  const std::uint64_t free_bytes = free_bytes_of(config_.data_dir);
  const bool disk_ok = free_bytes >= kMinFreeBytes;
  const bool draining = admission_.draining();
  r.ready = store_ok && device.status == "ok" && disk_ok && !draining;
  r.status = r.ready ? "ready" : draining ? "draining" : "not_ready";
  r.checks = {{"store", store},
              {"device", {{"status", device.status}, {"name", device.name}}},
              {"disk", {{"status", disk_ok ? "ok" : "low"}, {"free_bytes", free_bytes}}},
              {"queue", {{"length", queue_.size()}, {"max", config_.max_queue}}},
              {"draining", draining}};
  return r;
}

std::vector<Gauge> JobService::gauges() {
  const std::size_t running = workers_.running_count();
  return {{"texwarpd_queue_length", "Jobs waiting for a worker.", static_cast<double>(queue_.size())},
          {"texwarpd_queue_capacity", "Queued jobs beyond which submissions get 429.",
           static_cast<double>(config_.max_queue)},
          {"texwarpd_jobs_running", "Jobs running now.", static_cast<double>(running)},
          {"texwarpd_workers", "Worker threads.", static_cast<double>(config_.workers)},
          {"texwarpd_draining", "1 while shutting down.", draining() ? 1.0 : 0.0}};
}

}  // namespace texwarp::server
