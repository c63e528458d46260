// JobAdmission: how a job gets in. Decodes the body (malformed JSON, invalid job), keeps Idempotency-Keys (one
// request per key at a time; a replay returns the original job, another body is refused), holds the bounded queue's
// limit and its Retry-After, stores inline images as blobs, validates the job against the limits, inserts it durably
// and queues it. While the server drains, nothing gets in.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include "texwarp/proto/job_spec.hpp"
#include "texwarp/server/blob_store.hpp"
#include "texwarp/server/job_queue.hpp"
#include "texwarp/server/job_store.hpp"
#include "texwarp/server/metrics.hpp"
#include "texwarp/server/server_config.hpp"
#include "texwarp/server/server_input_resolver.hpp"

namespace texwarp::server {

struct Admitted {
  JobRow row;
  bool replayed = false;  // an Idempotency-Key seen before with the same body: the original job
};

class JobAdmission {
 public:
  JobAdmission(const ServerConfig& config, JobStore& store, BlobStore& blobs, Metrics& metrics,
               ServerInputResolver& resolver, JobQueue& queue);

  // ServiceError for every refusal: kMalformedJson, kInvalidJob, kIdempotencyKeyReused, kQueueFull (with a
  // Retry-After from the queue's length), kShuttingDown, kStorageFull.
  Admitted submit(const std::string& body, const std::optional<std::string>& idempotency_key);
  // While a request with this key is being processed, a second one gets kIdempotencyKeyInUse; the token releases
  // the key.
  std::shared_ptr<void> claim_idempotency_key(const std::string& key);

  // From now on new jobs are refused with kShuttingDown.
  void begin_drain() { draining_.store(true); }
  bool draining() const { return draining_.load(); }
  // Seconds a client should wait before retrying when the queue is full.
  int retry_after_s() const;

 private:
  // Stores an inline image as a blob and validates the job against the limits.
  void prepare(proto::JobSpec& spec);
  // The durable insert; the job inserted before with the same Idempotency-Key, if any.
  std::optional<JobRow> insert(const NewJob& job);

  const ServerConfig& config_;
  JobStore& store_;
  BlobStore& blobs_;
  Metrics& metrics_;
  ServerInputResolver& resolver_;
  JobQueue& queue_;
  std::atomic<bool> draining_{false};
  std::mutex keys_mutex_;
  std::set<std::string> keys_in_flight_;
};

}  // namespace texwarp::server
