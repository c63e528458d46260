// Many clients at once against one texwarpd, with a queue small enough that it pushes back (429 + Retry-After):
// every submission ends accepted exactly once (idempotency keys make the retries safe), every job succeeds, none is
// lost or duplicated.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <regex>
#include <set>
#include <thread>

#include "raw_http.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/client/client.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;

TEST(Concurrency, ManyClientsNoErrorsNoLostJobs) {
  const fs::path dir = test_folder();
  ServerProcess server(dir / "data",
                       {"--max-queue", "2", "--workers", "2", "--threads-per-job", "1", "--io-threads", "2"});
  constexpr int kClients = 8;
  constexpr int kJobsEach = 4;
  const proto::JobSpec job = proto::decode_job_spec(image_job());
  std::mutex mutex;
  std::set<std::string> ids;
  std::vector<std::string> errors;
  std::atomic<int> succeeded{0};
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::thread> clients;
  clients.reserve(kClients);
  for (int t = 0; t < kClients; ++t) {
    clients.emplace_back([&, t] {
      client::ClientOptions options;
      options.server = server.url();
      options.max_retries = 100;  // the queue is small on purpose: keep coming back as told
      options.max_retry_delay = std::chrono::milliseconds(2000);
      client::Client c(options);
      for (int i = 0; i < kJobsEach; ++i) {
        const auto submitted = c.submit(job, "client-" + std::to_string(t) + "-job-" + std::to_string(i));
        if (!submitted.ok()) {
          std::lock_guard lock(mutex);
          errors.push_back(submitted.error().message);
          continue;
        }
        {
          std::lock_guard lock(mutex);
          ids.insert(submitted->id);
        }
        const auto done = c.wait(submitted->id);
        if (done.ok() && done->state == proto::JobState::kSucceeded) {
          ++succeeded;
        } else {
          std::lock_guard lock(mutex);
          errors.push_back(done.ok() ? proto::to_string(done->state) : done.error().message);
        }
      }
    });
  }
  for (auto& t : clients) t.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(errors.empty()) << errors.size() << " errors, first: " << (errors.empty() ? "" : errors[0]);
  EXPECT_EQ(ids.size(), static_cast<std::size_t>(kClients * kJobsEach));
  EXPECT_EQ(succeeded.load(), kClients * kJobsEach);
  // The server has exactly these jobs, all succeeded.
  const nlohmann::json page = http_request(server.port(), "GET", "/v1/jobs?limit=500").json();
  std::set<std::string> listed;
  for (const auto& j : page["jobs"]) {
    listed.insert(j["id"]);
    EXPECT_EQ(j["state"], "succeeded");
  }
  EXPECT_EQ(listed, ids);
  // The queue did push back, and the clients' retries got through.
  const std::string metrics = http_request(server.port(), "GET", "/metrics").body;
  std::smatch m;
  const bool pushed_back = std::regex_search(
      metrics, m, std::regex(R"(texwarpd_http_requests_total\{route="/v1/jobs",method="POST",status="429"\} (\d+))"));
  std::printf("concurrency: %d clients x %d jobs (64², 4 features, cpu): %.2f s, %.1f jobs/s, %s 429 answers\n",
              kClients, kJobsEach, seconds, kClients * kJobsEach / seconds, pushed_back ? m[1].str().c_str() : "no");
  EXPECT_TRUE(pushed_back);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace texwarp::testing
