// How jobs get in: see job_admission.hpp.
#include "texwarp/server/job_admission.hpp"

#include <malloc.h>

#include <algorithm>
#include <cmath>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_batch_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/server/job_id.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/retry_after.hpp"
#include "texwarp/server/service_error.hpp"
#include "texwarp/server/sha256.hpp"
#include "texwarp/server/storage_full.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {
namespace {

constexpr int kMaxEstimateS = 120;                    // Retry-After from this node's mean run time, at most
constexpr std::size_t kTrimAfterBodyBytes = 8 << 20;  // a job body this large: heap given back after its parse

// The parse of a large body leaves millions of small freed blocks that glibc keeps resident (a 32 MiB array of
// empty objects: +680 MB for good); trimmed once the parsed value is gone (this guard is destroyed last).
struct TrimHeapAfter {
  bool large = false;
  ~TrimHeapAfter() {
    if (large) ::malloc_trim(0);
  }
};

ServiceError invalid_job(const InputError& e) {
  return ServiceError(ErrorKind::kInvalidJob, e.message_without_file(), e.where().without_file().str());
}

nlohmann::json parse_body(const std::string& body) {
  try {
    return proto::parse_json(body, "request body");
  } catch (const proto::DuplicateKeyError& e) {  // well-formed JSON whose meaning is ambiguous: an invalid job
    throw invalid_job(e);
  } catch (const InputError& e) {
    throw ServiceError(ErrorKind::kMalformedJson, e.what());
  }
}

// A job inserted before with this Idempotency-Key: replayed when the body is the same, else refused (`where`
// names the job of a batch).
void check_replay(const JobRow& existing, const std::string& fingerprint, const std::string& where = {}) {
  if (existing.body_sha256 == fingerprint) return;
  throw ServiceError(ErrorKind::kIdempotencyKeyReused,
                     "this Idempotency-Key was used for job " + existing.id + " with a different body" +
                         (where.empty() ? "" : " (" + where + ")") + "; use a new key for a new job",
                     where);
}

// The Idempotency-Key of a batch's job i.
// A batch's job i is stored under "<key> #<i>": a request's own key never holds a space, so a batch's jobs never
// share a key with a single job (a job sent with "z#0" is not job 0 of the batch "z").
std::string batch_key(const std::string& key, std::size_t i) { return key + " #" + std::to_string(i); }

// The row of an accepted job: a fresh id, its spec in the canonical form.
NewJob new_job(const proto::JobSpec& spec, const std::string& fingerprint,
               const std::optional<std::string>& idempotency_key) {
  NewJob job;
  job.id = new_job_id();
  job.name = spec.name;
  job.kind = spec.kind();
  job.priority = spec.priority;
  job.labels = spec.labels;
  job.spec_json = proto::safe_dump(proto::encode_job_spec(spec));
  job.body_sha256 = fingerprint;
  job.idempotency_key = idempotency_key;
  job.created_ms = now_ms();
  return job;
}

}  // namespace

JobAdmission::JobAdmission(const ServerConfig& config, JobStore& store, BlobStore& blobs, Metrics& metrics,
                           ServerInputResolver& resolver, WorkSignal& work)
    : config_(config),
      store_(store),
      blobs_(blobs),
      metrics_(metrics),
      resolver_(resolver),
      work_(work),
      started_ms_(now_ms()) {}

std::shared_ptr<void> JobAdmission::claim_idempotency_key(const std::string& key) {
  std::lock_guard lock(keys_mutex_);
  if (!keys_in_flight_.insert(key).second) {
    throw ServiceError(ErrorKind::kIdempotencyKeyInUse,
                       "another request with this Idempotency-Key is being processed right now; retry after it has "
                       "been answered to get its result");
  }
  return std::shared_ptr<void>(nullptr, [this, key](void*) {
    std::lock_guard release(keys_mutex_);
    keys_in_flight_.erase(key);
  });
}

void JobAdmission::check_room(std::size_t adding) const {
  if (adding > config_.max_queue) {  // never fits, however long the client waits: not a 429 to retry
    throw ServiceError(ErrorKind::kInvalidJob,
                       "this batch adds " + std::to_string(adding) + " jobs and this server queues at most " +
                           std::to_string(config_.max_queue) + " (--max-queue); send batches of at most " +
                           std::to_string(config_.max_queue) + " jobs",
                       "$.jobs");
  }
  const std::int64_t queued = store_.count(proto::JobState::kQueued);
  if (static_cast<std::size_t>(queued) + adding <= config_.max_queue) return;
  const std::string what = adding == 1 ? "" : " (this batch adds " + std::to_string(adding) + ")";
  throw ServiceError(ErrorKind::kQueueFull, std::to_string(queued) + " jobs are waiting, the most is " +
                                                std::to_string(config_.max_queue) + what +
                                                "; retry after the time given")
      .retry_after(retry_after_s(queued));
}

void JobAdmission::check_open(bool replay_possible) const {
  if (!draining_.load() || replay_possible) return;
  throw ServiceError(ErrorKind::kShuttingDown, "the server is shutting down; retry shortly");
}

Admitted JobAdmission::submit(const std::string& body, const std::optional<std::string>& idempotency_key) {
  check_open(idempotency_key.has_value());
  const TrimHeapAfter trim{body.size() >= kTrimAfterBodyBytes};
  NewJob job;
  {
    const nlohmann::json json = parse_body(body);
    proto::JobSpec spec;
    try {
      spec = proto::decode_job_spec(json);
    } catch (const InputError& e) {
      throw invalid_job(e);
    }
    const std::string fingerprint = sha256_hex(proto::safe_dump(json));
    // A replay is not new work: answered before the drain and the queue's room are looked at.
    if (idempotency_key) {
      if (auto existing = store_.find_by_idempotency_key(*idempotency_key)) {
        check_replay(*existing, fingerprint);
        return {std::move(*existing), true};
      }
    }
    check_open(false);
    check_room(1);
    prepare(spec, JsonPath{});
    job = new_job(spec, fingerprint, idempotency_key);
  }
  const Inserted inserted = std::move(insert({job}).front());
  if (inserted.existed) {  // another node inserted this key since the look above
    check_replay(inserted.row, job.body_sha256);
    return {inserted.row, true};
  }
  work_.notify();
  metrics_.job_submitted(proto::to_string(job.kind));
  log_event(LogLevel::kInfo, "job accepted",
            {{"job", job.id}, {"kind", proto::to_string(job.kind)}, {"name", job.name}, {"priority", job.priority}});
  return {inserted.row, false};
}

AdmittedBatch JobAdmission::submit_batch(const std::string& body, const std::optional<std::string>& idempotency_key) {
  check_open(idempotency_key.has_value());
  const TrimHeapAfter trim{body.size() >= kTrimAfterBodyBytes};
  const JsonPath items = JsonPath{}.key("jobs");
  std::vector<NewJob> jobs;
  {
    const nlohmann::json json = parse_body(body);
    proto::JobBatch batch;
    try {
      batch = proto::decode_job_batch(json);
    } catch (const InputError& e) {
      throw invalid_job(e);
    }
    std::vector<std::string> fingerprints;
    for (std::size_t i = 0; i < batch.jobs.size(); ++i) {
      fingerprints.push_back(sha256_hex(proto::safe_dump(json["jobs"][i])));
    }
    // Jobs of this key stored before, looked at before anything is stored: another body under one of their keys is
    // refused with nothing inserted, and a whole replay is answered with the original jobs (not new work: before
    // the drain and the queue's room are looked at).
    std::size_t existing = 0;
    AdmittedBatch replay;
    replay.replayed = true;
    for (std::size_t i = 0; idempotency_key && i < batch.jobs.size(); ++i) {
      auto row = store_.find_by_idempotency_key(batch_key(*idempotency_key, i));
      if (!row) continue;
      check_replay(*row, fingerprints[i], items.index(i).str());
      ++existing;
      replay.rows.push_back(std::move(*row));
    }
    if (existing > 0 && existing == batch.jobs.size()) return replay;
    check_open(false);
    check_room(batch.jobs.size() - existing);
    for (std::size_t i = 0; i < batch.jobs.size(); ++i) prepare(batch.jobs[i], items.index(i));
    for (std::size_t i = 0; i < batch.jobs.size(); ++i) {
      std::optional<std::string> key;
      if (idempotency_key) key = batch_key(*idempotency_key, i);
      jobs.push_back(new_job(batch.jobs[i], fingerprints[i], key));
    }
  }
  const std::vector<Inserted> inserted = insert(jobs);
  AdmittedBatch out;
  std::size_t existed = 0;
  for (std::size_t i = 0; i < inserted.size(); ++i) {
    if (inserted[i].existed) {
      // Stored before (looked at above), or by another node since: a different body is refused (the rest of the
      // batch is stored by then only in that race).
      check_replay(inserted[i].row, jobs[i].body_sha256, items.index(i).str());
      ++existed;
    }
    out.rows.push_back(inserted[i].row);
  }
  out.replayed = existed == inserted.size();
  if (existed < inserted.size()) {
    work_.notify();
    for (std::size_t i = 0; i < inserted.size(); ++i) {
      if (!inserted[i].existed) metrics_.job_submitted(proto::to_string(jobs[i].kind));
    }
    log_event(LogLevel::kInfo, "job batch accepted",
              {{"jobs", inserted.size() - existed}, {"first", jobs.front().id}, {"last", jobs.back().id}});
  }
  return out;
}

void JobAdmission::prepare(proto::JobSpec& spec, const JsonPath& base) {
  try {
    // Inline images are stored as blobs: the stored job names them by id (a texture set's maps and UDIM tiles too).
    const auto store_inline = [&](proto::ImageSourceSpec& image) {
      for (proto::UdimTileSource& tile : image.tiles) {  // a UDIM texture's inline tiles too
        if (tile.data.empty()) continue;
        tile.blob = blobs_.put(tile.data).id;
        tile.data.clear();
      }
      if (image.kind != proto::ImageSourceSpec::Kind::kBase64) return;
      const proto::BlobInfo blob = blobs_.put(image.data);
      image.kind = proto::ImageSourceSpec::Kind::kBlob;
      image.blob = blob.id;
      image.data.clear();
    };
    store_inline(spec.image);
    for (proto::NamedImageSpec& entry : spec.images) store_inline(entry.source);
    runner::validate_job(spec, resolver_, config_.limits);
  } catch (const InputError& e) {
    if (base.is_root()) throw invalid_job(e);
    throw invalid_job(InputError(e.where().rebased(base), e.detail()));
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    log_event(LogLevel::kWarn, "job refused: storage full", {{"error", e.what()}});
    throw storage_full_error("the job's image could not be stored and the job was not accepted");
  }
}

std::vector<Inserted> JobAdmission::insert(const std::vector<NewJob>& jobs) {
  try {
    if (jobs.size() == 1) return {store_.insert(jobs.front())};
    return store_.insert_batch(jobs);
  } catch (const StoreUnavailable&) {
    throw;
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    log_event(LogLevel::kWarn, "job refused: storage full", {{"error", e.what()}});
    throw storage_full_error(jobs.size() == 1 ? "the job could not be recorded and was not accepted"
                                              : "the jobs could not be recorded and none was accepted");
  }
}

int JobAdmission::retry_after_s(std::int64_t queued) const {
  const std::int64_t now = now_ms();
  const FinishedSince recent = store_.finished_since(now - kThroughputWindowMs);
  if (const auto s =
          retry_after_from_throughput(queued, recent.count, observed_seconds(now, started_ms_, recent.oldest_ms))) {
    return *s;
  }
  const double mean = std::max(metrics_.mean_job_seconds(), 0.5);
  const double waiting = static_cast<double>(queued) - static_cast<double>(config_.max_queue) + 1.0;
  const double s = std::max(1.0, mean * std::max(waiting, 1.0) / config_.workers);
  return static_cast<int>(std::min<double>(std::ceil(s), kMaxEstimateS));
}

}  // namespace texwarp::server
