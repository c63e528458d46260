// JobAdmission: how jobs get in, one (POST /v1/jobs) or a batch all or none (POST /v1/jobs:batch). Decodes the body
// (malformed JSON, invalid job: every job of a batch validated before any is stored), keeps Idempotency-Keys (one
// request per key at a time on this node; across nodes the store's unique key makes one job; a replay returns the
// original job, another body is refused), refuses work when the store's queue is full (Retry-After from the queue's
// recent throughput), stores inline images as blobs, validates jobs against the limits, inserts them durably and
// wakes this node's idle workers. While the server drains, nothing gets in.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "texwarp/proto/job_spec.hpp"
#include "texwarp/server/blob_store.hpp"
#include "texwarp/server/job_store.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/server_input_resolver.hpp"
#include "texwarp/server/work_signal.hpp"

namespace texwarp::server {

struct Admitted {
  JobRow row;
  bool replayed = false;  // an Idempotency-Key seen before with the same body: the original job
};

struct AdmittedBatch {
  std::vector<JobRow> rows;  // in the batch's order
  bool replayed = false;     // every job was inserted before (the same Idempotency-Key and bodies)
};

class JobAdmission {
 public:
  JobAdmission(const ServerConfig& config, JobStore& store, BlobStore& blobs, Metrics& metrics,
               ServerInputResolver& resolver, WorkSignal& work);

  // ServiceError for every refusal: kMalformedJson, kInvalidJob, kIdempotencyKeyReused, kQueueFull (with its
  // Retry-After), kShuttingDown, kStorageFull; StoreUnavailable when the store cannot be reached. A replay (an
  // Idempotency-Key stored before, the same body) returns the original job even when the queue is full or the
  // server drains: it is not new work.
  Admitted submit(const std::string& body, const std::optional<std::string>& idempotency_key);
  // The same for {"jobs": [...]}: errors name $.jobs[<i>]…; the key applies to job i as "<key> #<i>". When every
  // job's key was stored before with the same body, the original jobs; another body under any of them is
  // kIdempotencyKeyReused before anything is stored.
  AdmittedBatch submit_batch(const std::string& body, const std::optional<std::string>& idempotency_key);
  // While a request with this key is being processed, a second one gets kIdempotencyKeyInUse; the token releases
  // the key.
  std::shared_ptr<void> claim_idempotency_key(const std::string& key);

  // From now on new jobs are refused with kShuttingDown.
  void begin_drain() { draining_.store(true); }
  bool draining() const { return draining_.load(); }
  // Seconds a client should wait before retrying when `queued` jobs wait: the time the queue's recent throughput
  // (jobs finished on any node in the last 5 minutes, over the part of those minutes actually observed: see
  // retry_after.hpp) takes to run them, 1 to 600 s; before 3 jobs finished, an estimate from this node's mean run
  // time.
  int retry_after_s(std::int64_t queued) const;

 private:
  // Refuses new work while draining (kShuttingDown); `replay_possible`: not yet, a replay is answered even then.
  void check_open(bool replay_possible) const;
  // Refuses `adding` more jobs when the queue has no room for them.
  void check_room(std::size_t adding) const;
  // Stores an inline image as a blob and validates the job against the limits; errors placed under `base`.
  void prepare(proto::JobSpec& spec, const JsonPath& base);
  // The durable inserts, all or nothing.
  std::vector<Inserted> insert(const std::vector<NewJob>& jobs);

  const ServerConfig& config_;
  JobStore& store_;
  BlobStore& blobs_;
  Metrics& metrics_;
  ServerInputResolver& resolver_;
  WorkSignal& work_;
  const std::int64_t started_ms_;  // this node's start (epoch ms): the throughput is not observed before it
  std::atomic<bool> draining_{false};
  std::mutex keys_mutex_;
  std::set<std::string> keys_in_flight_;
};

}  // namespace texwarp::server
