// Load test (label "soak": not run by CI; `ctest --test-dir build -L soak`): client threads submitting small image jobs
// to one texwarpd on loopback for a bounded time and count, then status reads as fast as they come. Prints jobs/s,
// end-to-end latency percentiles, reads/s and how often the queue pushed back; fails on any lost or failed job.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "process_memory.hpp"
#include "raw_http.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/client/client.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : fallback;
}

// Requests answered with a 5xx status, summed over the server's request counters.
long server_errors(const std::string& metrics) {
  long total = 0;
  std::istringstream lines(metrics);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] == '#' || line.find("status=\"5") == std::string::npos) continue;
    total += std::atol(line.substr(line.rfind(' ') + 1).c_str());
  }
  return total;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
}

TEST(Load, SmallJobsFromManyClients) {
  const int clients = env_int("TEXWARP_LOAD_CLIENTS", 16);
  const int max_jobs = env_int("TEXWARP_LOAD_JOBS", 600);
  const double max_seconds = env_int("TEXWARP_LOAD_SECONDS", 60);
  const fs::path dir = test_folder();
  ServerProcess server(dir / "data",
                       {"--workers", "2", "--threads-per-job", "1", "--max-queue", "64", "--log-level", "warn"});
  const proto::JobSpec job = proto::decode_job_spec(image_job());
  const double rss_start = static_cast<double>(process_memory_kib(server.pid(), "VmRSS")) / 1024.0;

  // One client, one job at a time: the end-to-end latency of a small job on an idle server (submit → wait →
  // fetch of both result files).
  std::vector<double> alone;
  {
    client::ClientOptions options;
    options.server = server.url();
    client::Client c(options);
    client::WaitOptions wait;
    wait.poll_min = std::chrono::milliseconds(2);
    wait.poll_max = std::chrono::milliseconds(20);
    for (int i = 0; i < 30; ++i) {
      const auto t0 = Clock::now();
      const auto fetched = c.run(job, (dir / ("alone-" + std::to_string(i))).string(), wait);
      ASSERT_TRUE(fetched.ok()) << fetched.error().message;
      alone.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
  }
  std::printf("latency: one client, small job (64², 4 features, cpu) submit → wait → fetch: p50 %.1f ms, "
              "min %.1f ms, max %.1f ms over %zu jobs\n",
              1e3 * percentile(alone, 0.5), 1e3 * percentile(alone, 0.0), 1e3 * percentile(alone, 1.0), alone.size());

  std::atomic<int> issued{0};
  std::mutex mutex;
  std::vector<double> latencies;
  std::set<std::string> ids;
  std::vector<std::string> failures;
  const auto start = Clock::now();
  const auto deadline = start + std::chrono::duration<double>(max_seconds);
  std::vector<std::thread> threads;
  threads.reserve(static_cast<std::size_t>(clients));
  for (int t = 0; t < clients; ++t) {
    threads.emplace_back([&] {
      client::ClientOptions options;
      options.server = server.url();
      options.max_retries = 1000;
      options.max_retry_delay = std::chrono::milliseconds(1000);
      client::Client c(options);
      client::WaitOptions wait;
      wait.poll_min = std::chrono::milliseconds(5);
      wait.poll_max = std::chrono::milliseconds(100);
      while (issued.fetch_add(1) < max_jobs && Clock::now() < deadline) {
        const auto t0 = Clock::now();
        const auto submitted = c.submit(job);
        const auto done =
            submitted.ok() ? c.wait(submitted->id, wait) : client::Result<proto::JobStatus>(submitted.error());
        const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        std::lock_guard lock(mutex);
        if (!done.ok() || done->state != proto::JobState::kSucceeded) {
          failures.push_back(done.ok() ? proto::to_string(done->state) : done.error().message);
          continue;
        }
        ids.insert(done->id);
        latencies.push_back(seconds);
      }
    });
  }
  for (auto& t : threads) t.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();

  // Reads: job status as fast as the clients can ask.
  std::atomic<long> reads{0};
  const std::string some_id = ids.empty() ? "job_aaaaaaaaaaaaaaaaaaaaaaaaaa" : *ids.begin();
  const auto read_start = Clock::now();
  std::vector<std::thread> readers;
  readers.reserve(static_cast<std::size_t>(clients));
  for (int t = 0; t < clients; ++t) {
    readers.emplace_back([&] {
      client::ClientOptions options;
      options.server = server.url();
      client::Client c(options);
      while (Clock::now() - read_start < std::chrono::seconds(3)) {
        if (c.status(some_id).ok()) ++reads;
      }
    });
  }
  for (auto& t : readers) t.join();
  const double read_seconds = std::chrono::duration<double>(Clock::now() - read_start).count();

  const std::string metrics = http_request(server.port(), "GET", "/metrics").body;
  const auto pos = metrics.find(R"(route="/v1/jobs",method="POST",status="429"} )");
  const std::string pushbacks =
      pos == std::string::npos ? "0" : metrics.substr(pos + 46, metrics.find('\n', pos) - pos - 46);
  std::printf("server: %ld answers with a 5xx status; RSS %.1f MiB at start, %.1f MiB at the end\n",
              server_errors(metrics), rss_start,
              static_cast<double>(process_memory_kib(server.pid(), "VmRSS")) / 1024.0);
  EXPECT_EQ(server_errors(metrics), 0);
  std::printf("load: %d clients, %zu jobs (64², 4 features, cpu, 2 workers × 1 thread) in %.2f s: %.1f jobs/s; "
              "end-to-end latency p50 %.1f ms, p95 %.1f ms, p99 %.1f ms, max %.1f ms; %s submissions answered 429; "
              "status reads %.0f/s over %.1f s\n",
              clients, latencies.size(), elapsed, static_cast<double>(latencies.size()) / elapsed,
              1e3 * percentile(latencies, 0.5), 1e3 * percentile(latencies, 0.95), 1e3 * percentile(latencies, 0.99),
              1e3 * percentile(latencies, 1.0), pushbacks.c_str(), static_cast<double>(reads.load()) / read_seconds,
              read_seconds);
  EXPECT_TRUE(failures.empty()) << failures.size() << " failed, first: " << (failures.empty() ? "" : failures[0]);
  EXPECT_EQ(ids.size(), latencies.size());
  const nlohmann::json page = http_request(server.port(), "GET", "/v1/jobs?limit=500&state=succeeded").json();
  EXPECT_GE(page["jobs"].size(), std::min<std::size_t>(ids.size(), 500));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace texwarp::testing
