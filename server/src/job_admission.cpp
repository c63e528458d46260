// How a job gets in: see job_admission.hpp.
#include "texwarp/server/job_admission.hpp"

#include <malloc.h>

#include <algorithm>
#include <cmath>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/server/job_id.hpp"
#include "texwarp/server/json_log.hpp"
#include "texwarp/server/service_error.hpp"
#include "texwarp/server/sha256.hpp"
#include "texwarp/server/storage_full.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::server {
namespace {

constexpr int kMaxRetryAfterS = 120;
constexpr std::size_t kTrimAfterBodyBytes = 8 << 20;  // a job body this large: heap given back after its parse

// The parse of a large body leaves millions of small freed blocks that glibc keeps resident (a 32 MiB array of
// empty objects: +680 MB for good); trimmed once the parsed value is gone (this guard is destroyed last).
struct TrimHeapAfter {
  bool large = false;
  ~TrimHeapAfter() {
    if (large) ::malloc_trim(0);
  }
};

struct DecodedJob {
  proto::JobSpec spec;
  std::string fingerprint;  // SHA-256 of the body's canonical JSON: what an Idempotency-Key's replay must match
};

DecodedJob decode(const std::string& body) {
  nlohmann::json json;
  try {
    json = proto::parse_json(body, "request body");
  } catch (const proto::DuplicateKeyError& e) {  // well-formed JSON whose meaning is ambiguous: an invalid job
    throw ServiceError(ErrorKind::kInvalidJob, e.message_without_file(), e.where().without_file().str());
  } catch (const InputError& e) {
    throw ServiceError(ErrorKind::kMalformedJson, e.what());
  }
  DecodedJob out;
  try {
    out.spec = proto::decode_job_spec(json);
  } catch (const InputError& e) {
    throw ServiceError(ErrorKind::kInvalidJob, e.message_without_file(), e.where().without_file().str());
  }
  out.fingerprint = sha256_hex(proto::safe_dump(json));
  return out;
}

// A job inserted before with this Idempotency-Key: replayed when the body is the same, else refused.
Admitted replay_or_conflict(const JobRow& existing, const std::string& fingerprint) {
  if (existing.body_sha256 != fingerprint) {
    throw ServiceError(ErrorKind::kIdempotencyKeyReused, "this Idempotency-Key was used for job " + existing.id +
                                                             " with a different body; use a new key for a new job");
  }
  return Admitted{existing, true};
}

}  // namespace

JobAdmission::JobAdmission(const ServerConfig& config, JobStore& store, BlobStore& blobs, Metrics& metrics,
                           ServerInputResolver& resolver, JobQueue& queue)
    : config_(config), store_(store), blobs_(blobs), metrics_(metrics), resolver_(resolver), queue_(queue) {}

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

Admitted JobAdmission::submit(const std::string& body, const std::optional<std::string>& idempotency_key) {
  if (draining_.load()) throw ServiceError(ErrorKind::kShuttingDown, "the server is shutting down; retry shortly");
  const TrimHeapAfter trim{body.size() >= kTrimAfterBodyBytes};
  DecodedJob decoded = decode(body);
  if (idempotency_key) {
    if (auto existing = store_.find_by_idempotency_key(*idempotency_key)) {
      return replay_or_conflict(*existing, decoded.fingerprint);
    }
  }
  if (queue_.size() >= config_.max_queue) {
    throw ServiceError(ErrorKind::kQueueFull, "the server has " + std::to_string(config_.max_queue) +
                                                  " jobs waiting; retry after the time given")
        .retry_after(retry_after_s());
  }
  prepare(decoded.spec);
  NewJob job;
  job.id = new_job_id();
  job.name = decoded.spec.name;
  job.kind = decoded.spec.kind();
  job.spec_json = proto::safe_dump(proto::encode_job_spec(decoded.spec));
  job.body_sha256 = decoded.fingerprint;
  job.idempotency_key = idempotency_key;
  job.created_ms = now_ms();
  if (const auto existing = insert(job)) return replay_or_conflict(*existing, decoded.fingerprint);
  queue_.push(job.id);
  metrics_.job_submitted(proto::to_string(job.kind));
  log_event(LogLevel::kInfo, "job accepted",
            {{"job", job.id}, {"kind", proto::to_string(job.kind)}, {"name", job.name}});
  auto row = store_.get(job.id);
  if (!row) throw std::runtime_error("job " + job.id + " vanished after insert");
  return {std::move(*row), false};
}

void JobAdmission::prepare(proto::JobSpec& spec) {
  try {
    if (spec.image.kind == proto::ImageSourceSpec::Kind::kBase64) {
      const proto::BlobInfo blob = blobs_.put(spec.image.data);
      spec.image.kind = proto::ImageSourceSpec::Kind::kBlob;
      spec.image.blob = blob.id;
      spec.image.data.clear();
    }
    runner::validate_job(spec, resolver_, config_.limits);
  } catch (const InputError& e) {
    throw ServiceError(ErrorKind::kInvalidJob, e.message_without_file(), e.where().without_file().str());
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    log_event(LogLevel::kWarn, "job refused: storage full", {{"error", e.what()}});
    throw storage_full_error("the job's image could not be stored and the job was not accepted");
  }
}

std::optional<JobRow> JobAdmission::insert(const NewJob& job) {
  try {
    return store_.insert(job);
  } catch (const std::exception& e) {
    if (!is_storage_full(e)) throw;
    log_event(LogLevel::kWarn, "job refused: storage full", {{"error", e.what()}});
    throw storage_full_error("the job could not be recorded and was not accepted");
  }
}

int JobAdmission::retry_after_s() const {
  const double mean = std::max(metrics_.mean_job_seconds(), 0.5);
  const double waiting = static_cast<double>(queue_.size()) - static_cast<double>(config_.max_queue) + 1.0;
  const double s = std::max(1.0, mean * std::max(waiting, 1.0) / config_.workers);
  return static_cast<int>(std::min<double>(std::ceil(s), kMaxRetryAfterS));
}

}  // namespace texwarp::server
