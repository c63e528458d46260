// Metrics: counters and histograms of the service (HTTP requests by route and status, request and job durations,
// jobs by outcome, fenced runs and lost leases, blob uploads) rendered in the Prometheus text exposition format
// (version 0.0.4), with gauges (queue length, running jobs, nodes, ...) supplied at render time. Thread-safe.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace texwarp::server {

// `value` escaped for a label value inside double quotes (backslash, quote, newline).
std::string escape_label(const std::string& value);

class Histogram {
 public:
  explicit Histogram(std::vector<double> bounds);
  void observe(double value);
  // Lines for `name` with `labels` ("" or `route="x"`), cumulative buckets, +Inf, _sum and _count.
  void render(std::string& out, const std::string& name, const std::string& labels) const;

 private:
  std::vector<double> bounds_;
  std::vector<std::uint64_t> counts_;  // per bucket, not cumulative; one more for +Inf
  double sum_ = 0.0;
  std::uint64_t count_ = 0;
};

struct Gauge {
  std::string name;
  std::string help;
  double value = 0.0;
  std::string labels = {};  // `node="a",version="1"` or empty
};

class Metrics {
 public:
  void observe_request(const std::string& route, const std::string& method, int status, double seconds);
  void job_submitted(const std::string& kind);
  void job_finished(const std::string& kind, const std::string& state, double run_seconds);
  void blob_uploaded(std::uint64_t bytes, bool created);
  // A run's outcome refused by the store: another node held the job's lease by then.
  void job_fenced();
  // A heartbeat found a lease of this node's gone (expired and reclaimed): the run was stopped.
  void lease_lost();

  // Mean run time of the last jobs (seconds; 0 before any), for Retry-After estimates.
  double mean_job_seconds() const;

  std::string render(const std::vector<Gauge>& gauges) const;

 private:
  mutable std::mutex mutex_;
  std::map<std::tuple<std::string, std::string, int>, std::uint64_t> requests_;  // route, method, status
  std::map<std::string, Histogram> request_seconds_;                             // by route
  std::map<std::string, std::uint64_t> submitted_;                               // by kind
  std::map<std::pair<std::string, std::string>, std::uint64_t> finished_;        // kind, state
  std::map<std::string, Histogram> job_seconds_;                                 // by kind
  std::uint64_t blob_uploads_ = 0;
  std::uint64_t blob_created_ = 0;
  std::uint64_t blob_bytes_ = 0;
  std::uint64_t fenced_ = 0;
  std::uint64_t leases_lost_ = 0;
  double recent_job_seconds_ = 0.0;  // exponential moving average
};

}  // namespace texwarp::server
