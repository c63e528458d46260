// The service as the routes see it (start-up, shutdown, reads): see job_service.hpp.
#include "texwarp/server/job_service.hpp"

#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <fstream>

#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/problem_details_codec.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/server/job_id.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/service_error.hpp"
#include "texwarp/server/storage_full.hpp"
#include "texwarp/server/timestamps.hpp"

#ifndef TEXWARP_VERSION
#define TEXWARP_VERSION "unknown"
#endif

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kMinFreeBytes = 64ULL << 20;  // /readyz: the data folder needs this much free space
constexpr int kAliveHeartbeats = 3;                   // a node seen within this many heartbeats is alive

std::string host_name() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "localhost";
  return name;
}

}  // namespace

JobService::JobService(const ServerConfig& config, JobStore& store, BlobStore& blobs, Metrics& metrics)
    : config_(config),
      store_(store),
      blobs_(blobs),
      metrics_(metrics),
      resolver_(blobs, config.input_roots),
      results_(config.data_dir),
      admission_(config, store, blobs, metrics, resolver_, work_),
      workers_(config, store, metrics, resolver_, work_, watchers_, results_, stop_),
      heartbeat_(config, store, workers_, work_),
      retention_(config, store, results_, stop_) {}

JobService::~JobService() { shutdown(0.0); }

void JobService::start(unsigned short port) {
  node_id_ = config_.node_id.empty() ? host_name() + ":" + std::to_string(port) : config_.node_id;
  // With SQLite this process is the only node (it holds the data folder's lock): every running job's lease is dead.
  // With a shared store only the leases of this node's earlier life are; the others expire and any node reclaims them.
  const Reclaimed r = config_.sqlite_store() ? store_.reclaim_expired(LLONG_MAX, config_.max_attempts)
                                             : store_.reclaim_expired(now_ms(), config_.max_attempts, node_id_);
  const std::size_t orphans = retention_.remove_orphans();
  log_event(LogLevel::kInfo, "recovered jobs",
            {{"node", node_id_},
             {"store", store_.backend()},
             {"queued", store_.count(proto::JobState::kQueued)},
             {"requeued", r.requeued.size()},
             {"canceled", r.canceled},
             {"failed", r.failed},
             {"orphaned_results_removed", orphans},
             {"blob_temporaries_removed", blobs_.temporaries_removed()}});
  NodeInfo node;
  node.id = node_id_;
  node.address = (config_.host.find(':') != std::string::npos ? "[" + config_.host + "]" : config_.host) + ":" +
                 std::to_string(port);
  node.version = TEXWARP_VERSION;
  node.workers = config_.workers;
  node.pid = static_cast<std::int64_t>(::getpid());
  node.started_ms = now_ms();
  node.last_seen_ms = node.started_ms;
  heartbeat_.start(node, stop_);
  workers_.start(node_id_);
  retention_.start();
}

void JobService::shutdown(double grace_s) {
  admission_.begin_drain();
  if (stop_.set() && !workers_.started()) return;
  workers_.stop(grace_s);
  heartbeat_.stop(true);
  retention_.join();
}

SubmitResult JobService::submit(const std::string& body, const std::optional<std::string>& idempotency_key) {
  const Admitted admitted = admission_.submit(body, idempotency_key);
  return {to_status(admitted.row), admitted.replayed};
}

BatchResult JobService::submit_batch(const std::string& body, const std::optional<std::string>& idempotency_key) {
  const AdmittedBatch admitted = admission_.submit_batch(body, idempotency_key);
  BatchResult out;
  out.replayed = admitted.replayed;
  for (const auto& row : admitted.rows) out.jobs.push_back(to_status(row));
  return out;
}

proto::JobStatus JobService::to_status(const JobRow& row) {
  proto::JobStatus s;
  s.id = row.id;
  s.name = row.name;
  s.kind = row.kind;
  s.state = row.state;
  s.attempts = row.attempts;
  s.cancel_requested = row.cancel_requested;
  s.priority = row.priority;
  s.labels = row.labels;
  s.node = row.node_id;
  s.created_at = rfc3339_utc(row.created_ms);
  if (row.started_ms) s.started_at = rfc3339_utc(*row.started_ms);
  if (row.finished_ms) s.finished_at = rfc3339_utc(*row.finished_ms);
  s.progress = row.state == proto::JobState::kSucceeded ? 100 : row.progress;
  if (row.state == proto::JobState::kRunning) {
    // Running here: the live value; on another node: what its holder stored with its last heartbeat.
    if (const auto running = workers_.progress(row.id)) s.progress = std::max(*running, row.progress);
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

proto::JobPage JobService::list(const std::string& cursor, int limit, std::optional<proto::JobState> state,
                                const Labels& labels) {
  ListQuery query;
  if (!cursor.empty()) {
    char* end = nullptr;
    const long long seq = std::strtoll(cursor.c_str(), &end, 10);
    if (*end != '\0' || seq <= 0 || cursor.size() > 19) {
      throw ServiceError(ErrorKind::kBadQuery,
                         "cursor: not a cursor this server gave out (use next_cursor of the previous page)", "?cursor");
    }
    query.before_seq = seq;
  }
  query.limit = limit + 1;
  query.state = state;
  query.labels = labels;
  const std::vector<JobRow> rows = store_.list(query);
  proto::JobPage page;
  for (std::size_t i = 0; i < rows.size() && static_cast<int>(i) < limit; ++i) page.jobs.push_back(to_status(rows[i]));
  if (static_cast<int>(rows.size()) > limit)
    page.next_cursor = std::to_string(rows[static_cast<std::size_t>(limit) - 1].seq);
  return page;
}

std::variant<DeleteResult, JobRow> JobService::cancel_unfinished(const std::string& id) {
  if (!is_job_id(id)) throw job_not_found(id);
  CancelOutcome outcome = CancelOutcome::kNotFound;
  try {
    outcome = store_.request_cancel(id, now_ms());
  } catch (const StoreUnavailable&) {
    throw;
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    // The store cannot record the request, but a job running here still stops: its end (canceled) is recorded
    // once there is space again.
    if (!workers_.cancel_running(id)) throw storage_full_error("the cancellation could not be recorded");
    log_event(LogLevel::kWarn, "cancellation kept in memory: storage full", {{"job", id}, {"error", e.what()}});
    auto row = store_.get(id);
    if (!row) throw job_not_found(id);
    row->cancel_requested = true;
    return DeleteResult{DeleteResult::Action::kCancelRequested, to_status(*row)};
  }
  if (outcome == CancelOutcome::kNotFound) throw job_not_found(id);
  if (outcome == CancelOutcome::kRequested) workers_.cancel_running(id);  // running here: at once
  auto row = store_.get(id);
  if (!row) throw job_not_found(id);
  if (outcome == CancelOutcome::kCanceled) {
    metrics_.job_finished(proto::to_string(row->kind), "canceled", 0.0);
    log_event(LogLevel::kInfo, "job canceled while queued", {{"job", id}});
    watchers_.changed(id);
    return DeleteResult{DeleteResult::Action::kCanceled, to_status(*row)};
  }
  if (outcome == CancelOutcome::kRequested)
    return DeleteResult{DeleteResult::Action::kCancelRequested, to_status(*row)};
  return std::move(*row);
}

DeleteResult JobService::cancel(const std::string& id) {
  auto done = cancel_unfinished(id);
  if (auto* result = std::get_if<DeleteResult>(&done)) return std::move(*result);
  const JobRow& row = std::get<JobRow>(done);
  const std::string state = proto::to_string(row.state);
  throw ServiceError(ErrorKind::kJobFinished, "job " + id + " already finished (" + state +
                                                  "); nothing was changed (DELETE /v1/jobs/" + id +
                                                  " purges a finished job)");
}

DeleteResult JobService::remove(const std::string& id) {
  auto done = cancel_unfinished(id);
  if (auto* result = std::get_if<DeleteResult>(&done)) return std::move(*result);
  const JobRow row = std::move(std::get<JobRow>(done));
  // Finished: purge its row, then its files (a folder whose row is gone is an orphan the sweep would remove anyway).
  DeleteResult out{DeleteResult::Action::kPurged, to_status(row)};
  const PurgeOutcome purged = store_.purge(id);
  if (purged == PurgeOutcome::kNotFound) throw job_not_found(id);
  if (purged == PurgeOutcome::kNotFinished) throw std::logic_error("job " + id + " was finished and is not now");
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(results_.root(), ec)) {
    if (ResultFolders::parse(entry.path().filename().string()).job_id != id) continue;
    std::error_code rec;
    fs::remove_all(entry.path(), rec);
  }
  log_event(LogLevel::kInfo, "job purged", {{"job", id}, {"state", proto::to_string(row.state)}});
  watchers_.changed(id);
  return out;
}

fs::path JobService::served_folder(const JobRow& row) const {
  return results_.folder(row.result_folder.empty() ? row.id : row.result_folder);
}

JobRow JobService::succeeded_row(const std::string& id) {
  if (!is_job_id(id)) throw job_not_found(id);
  auto row = store_.get(id);
  if (!row) throw job_not_found(id);
  if (row->state != proto::JobState::kSucceeded) {
    const std::string state = proto::to_string(row->state);
    throw ServiceError(ErrorKind::kNoResult,
                       "job " + id + " is " + state +
                           (proto::is_terminal(row->state)
                                ? "; only a succeeded job has a result"
                                : "; its result is available once it has succeeded (GET /v1/jobs/" + id + ")"));
  }
  return std::move(*row);
}

proto::JobResult JobService::result(const std::string& id) {
  const JobRow row = succeeded_row(id);
  proto::JobResult result = proto::decode_job_result(nlohmann::json::parse(row.result_json));
  const fs::path report = served_folder(row) / runner::kReportFile;
  std::ifstream in(report);
  if (!in) throw std::runtime_error("the report of succeeded job " + id + " is missing");
  result.report_json = nlohmann::json::parse(in).dump();
  return result;
}

fs::path JobService::result_file(const std::string& id, const std::string& name, std::string* media_type,
                                 std::string* sha256) {
  const JobRow row = [&] {
    try {
      return succeeded_row(id);
    } catch (const ServiceError& e) {
      if (e.kind() == ErrorKind::kNoResult) {
        throw ServiceError(ErrorKind::kNotFound, "job " + id + " has no result files: " + e.detail());
      }
      throw;
    }
  }();
  const proto::JobResult r = proto::decode_job_result(nlohmann::json::parse(row.result_json));
  for (const auto& f : r.files) {
    if (f.name == name) {
      *media_type = f.media_type;
      *sha256 = f.sha256;
      return served_folder(row) / f.name;
    }
  }
  throw ServiceError(ErrorKind::kNotFound, "job " + id + " has no file \"" + name.substr(0, 64) + "\" (GET /v1/jobs/" +
                                               id + "/result lists them)");
}

proto::NodeList JobService::nodes() {
  const std::int64_t now = now_ms();
  const auto alive_ms = static_cast<std::int64_t>(kAliveHeartbeats * config_.heartbeat_s * 1000.0);
  proto::NodeList list;
  for (const NodeInfo& n : store_.nodes()) {
    proto::NodeStatus s;
    s.id = n.id;
    s.address = n.address;
    s.version = n.version;
    s.workers = n.workers;
    s.pid = n.pid;
    s.started_at = rfc3339_utc(n.started_ms);
    s.last_seen_at = rfc3339_utc(n.last_seen_ms);
    s.alive = now - n.last_seen_ms <= alive_ms;
    s.running = n.running;
    list.nodes.push_back(std::move(s));
  }
  return list;
}

proto::BlobInfo JobService::adopt_blob(const fs::path& temp_file) {
  proto::BlobInfo info = [&] {
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
  nlohmann::json queue = {{"max", config_.max_queue}};
  try {
    queue["length"] = store_ok ? store_.count(proto::JobState::kQueued) : -1;
  } catch (const std::exception&) {
    queue["length"] = -1;
  }
  r.ready = store_ok && device.status == "ok" && disk_ok && !draining;
  r.status = r.ready ? "ready" : draining ? "draining" : "not_ready";
  r.checks = {{"store", store},
              {"device", {{"status", device.status}, {"name", device.name}}},
              {"disk", {{"status", disk_ok ? "ok" : "low"}, {"free_bytes", free_bytes}}},
              {"queue", std::move(queue)},
              {"draining", draining}};
  return r;
}

std::vector<Gauge> JobService::gauges() {
  const std::size_t running = workers_.running_count();
  const std::int64_t now = now_ms();
  const auto alive_ms = static_cast<std::int64_t>(kAliveHeartbeats * config_.heartbeat_s * 1000.0);
  const std::vector<NodeInfo> nodes = store_.nodes();
  const auto alive =
      std::count_if(nodes.begin(), nodes.end(), [&](const NodeInfo& n) { return now - n.last_seen_ms <= alive_ms; });
  return {{"texwarpd_queue_length", "Jobs waiting for a worker (on any node).",
           static_cast<double>(store_.count(proto::JobState::kQueued))},
          {"texwarpd_queue_capacity", "Queued jobs beyond which submissions get 429.",
           static_cast<double>(config_.max_queue)},
          {"texwarpd_jobs_running", "Jobs running on this node now.", static_cast<double>(running)},
          {"texwarpd_workers", "Worker threads.", static_cast<double>(config_.workers)},
          {"texwarpd_draining", "1 while shutting down.", draining() ? 1.0 : 0.0},
          {"texwarpd_nodes_alive", "Nodes of this store seen within 3 heartbeats.", static_cast<double>(alive)},
          {"texwarpd_node_info", "This node: its id, version and store (always 1).", 1.0,
           "node=\"" + escape_label(node_id_) + "\",version=\"" + escape_label(TEXWARP_VERSION) + "\",store=\"" +
               escape_label(store_.backend()) + "\""}};
}

}  // namespace texwarp::server
