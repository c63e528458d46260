// Prometheus text metrics: see metrics.hpp.
#include "texwarp/server/metrics.hpp"

#include <charconv>
#include <cmath>

namespace texwarp::server {
namespace {

const std::vector<double> kRequestBounds = {0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10};
const std::vector<double> kJobBounds = {0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 120, 300, 600, 1800};
constexpr double kJobAverageWeight = 0.2;

// The shortest text that reads back as the same double ("0.0025", not "0.0025000000000000001").
std::string number(double v) {
  if (std::isinf(v)) return v > 0 ? "+Inf" : "-Inf";
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, end) : std::string("NaN");
}

void header(std::string& out, const std::string& name, const char* type, const char* help) {
  out += "# HELP " + name + " " + help + "\n# TYPE " + name + " " + type + "\n";
}

}  // namespace

std::string escape_label(const std::string& v) {
  std::string out;
  for (char c : v) {
    if (c == '\\' || c == '"') out.push_back('\\');
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out.push_back(c);
  }
  return out;
}

Histogram::Histogram(std::vector<double> bounds) : bounds_(std::move(bounds)), counts_(bounds_.size() + 1, 0) {}

void Histogram::observe(double value) {
  std::size_t i = 0;
  while (i < bounds_.size() && value > bounds_[i]) ++i;
  ++counts_[i];
  sum_ += value;
  ++count_;
}

void Histogram::render(std::string& out, const std::string& name, const std::string& labels) const {
  const std::string sep = labels.empty() ? "" : labels + ",";
  std::uint64_t cumulative = 0;
  for (std::size_t i = 0; i < bounds_.size(); ++i) {
    cumulative += counts_[i];
    out.append(name).append("_bucket{").append(sep).append("le=\"").append(number(bounds_[i])).append("\"} ");
    out.append(std::to_string(cumulative)).append("\n");
  }
  cumulative += counts_.back();
  out += name + "_bucket{" + sep + "le=\"+Inf\"} " + std::to_string(cumulative) + "\n";
  const std::string braces = labels.empty() ? "" : "{" + labels + "}";
  out += name + "_sum" + braces + " " + number(sum_) + "\n";
  out += name + "_count" + braces + " " + std::to_string(count_) + "\n";
}

void Metrics::observe_request(const std::string& route, const std::string& method, int status, double seconds) {
  std::lock_guard lock(mutex_);
  ++requests_[{route, method, status}];
  request_seconds_.try_emplace(route, kRequestBounds).first->second.observe(seconds);
}

void Metrics::job_submitted(const std::string& kind) {
  std::lock_guard lock(mutex_);
  ++submitted_[kind];
}

void Metrics::job_finished(const std::string& kind, const std::string& state, double run_seconds) {
  std::lock_guard lock(mutex_);
  ++finished_[{kind, state}];
  job_seconds_.try_emplace(kind, kJobBounds).first->second.observe(run_seconds);
  recent_job_seconds_ = recent_job_seconds_ == 0.0
                            ? run_seconds
                            : (1.0 - kJobAverageWeight) * recent_job_seconds_ + kJobAverageWeight * run_seconds;
}

void Metrics::blob_uploaded(std::uint64_t bytes, bool created) {
  std::lock_guard lock(mutex_);
  ++blob_uploads_;
  if (created) {
    ++blob_created_;
    blob_bytes_ += bytes;
  }
}

void Metrics::job_fenced() {
  std::lock_guard lock(mutex_);
  ++fenced_;
}

void Metrics::lease_lost() {
  std::lock_guard lock(mutex_);
  ++leases_lost_;
}

double Metrics::mean_job_seconds() const {
  std::lock_guard lock(mutex_);
  return recent_job_seconds_;
}

std::string Metrics::render(const std::vector<Gauge>& gauges) const {
  std::lock_guard lock(mutex_);
  std::string out;
  header(out, "texwarpd_http_requests_total", "counter", "HTTP requests answered, by route, method and status.");
  for (const auto& [key, n] : requests_) {
    const auto& [route, method, status] = key;
    out += "texwarpd_http_requests_total{route=\"" + escape_label(route) + "\",method=\"" + escape_label(method) +
           "\",status=\"" + std::to_string(status) + "\"} " + std::to_string(n) + "\n";
  }
  header(out, "texwarpd_http_request_duration_seconds", "histogram",
         "Time from a request's header to its answer being ready to send.");
  for (const auto& [route, h] : request_seconds_) {
    h.render(out, "texwarpd_http_request_duration_seconds", "route=\"" + escape_label(route) + "\"");
  }
  header(out, "texwarpd_jobs_submitted_total", "counter", "Jobs accepted (202), by kind.");
  for (const auto& [kind, n] : submitted_) {
    out += "texwarpd_jobs_submitted_total{kind=\"" + kind + "\"} " + std::to_string(n) + "\n";
  }
  header(out, "texwarpd_jobs_finished_total", "counter", "Jobs finished by this process, by kind and final state.");
  for (const auto& [key, n] : finished_) {
    out += "texwarpd_jobs_finished_total{kind=\"" + key.first + "\",state=\"" + key.second + "\"} " +
           std::to_string(n) + "\n";
  }
  header(out, "texwarpd_job_run_seconds", "histogram", "Time a worker spent on a job, by kind.");
  for (const auto& [kind, h] : job_seconds_) h.render(out, "texwarpd_job_run_seconds", "kind=\"" + kind + "\"");
  header(out, "texwarpd_blob_uploads_total", "counter", "Blob uploads received (deduplicated ones included).");
  out += "texwarpd_blob_uploads_total " + std::to_string(blob_uploads_) + "\n";
  header(out, "texwarpd_blobs_created_total", "counter", "Blob uploads that stored new bytes.");
  out += "texwarpd_blobs_created_total " + std::to_string(blob_created_) + "\n";
  header(out, "texwarpd_blob_bytes_stored_total", "counter", "Bytes of new blobs stored.");
  out += "texwarpd_blob_bytes_stored_total " + std::to_string(blob_bytes_) + "\n";
  header(out, "texwarpd_jobs_fenced_total", "counter",
         "Runs whose outcome the store refused because another node held the job's lease by then (job_fenced).");
  out += "texwarpd_jobs_fenced_total " + std::to_string(fenced_) + "\n";
  header(out, "texwarpd_leases_lost_total", "counter",
         "Runs stopped because a heartbeat found their lease expired and reclaimed (lease_lost).");
  out += "texwarpd_leases_lost_total " + std::to_string(leases_lost_) + "\n";
  for (const auto& g : gauges) {
    header(out, g.name, "gauge", g.help.c_str());
    out += g.name + (g.labels.empty() ? "" : "{" + g.labels + "}") + " " + number(g.value) + "\n";
  }
  return out;
}

}  // namespace texwarp::server
