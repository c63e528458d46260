// The library's contract beyond single calls: one Client shared by many threads (every job submitted once,
// each thread's answers its own, the connections reused), StopSource and StopToken, a wait stopped through its stop
// token while a long-poll is in flight, Result without exceptions (value_or; value() of an error aborts with the
// message), jobs as JSON text.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <mutex>
#include <set>
#include <thread>

#include "client_test_support.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/client/client.hpp"
#include "texwarp/client/job_json.hpp"
#include "texwarp/proto/job_spec_codec.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using client::ErrorCode;
using ::testing::HasSubstr;

TEST(SharedClient, OneClientManyThreads) {
  const fs::path dir = test_folder();
  ServerProcess server(dir / "data", {"--workers", "2", "--threads-per-job", "1"});
  client::Client c = client_for(server);
  constexpr int kThreads = 8;
  constexpr int kJobsEach = 3;
  const proto::JobSpec job = proto::decode_job_spec(image_job());
  std::mutex mutex;
  std::set<std::string> ids;
  std::vector<std::string> errors;
  std::vector<std::thread> threads;
  threads.reserve(kThreads);
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < kJobsEach; ++i) {
        proto::JobSpec mine = job;
        mine.name = "thread " + std::to_string(t) + " job " + std::to_string(i);
        const auto submitted = c.submit(mine);
        std::string error;
        if (!submitted) {
          error = submitted.error().message;
        } else {
          const auto done = c.wait(submitted->id);
          const auto status = c.status(submitted->id);  // each thread gets its own job's answer back
          const auto files = c.fetch_results(submitted->id, (dir / submitted->id).string());
          if (!done || done->state != proto::JobState::kSucceeded) error = "not succeeded: " + submitted->id;
          if (!status || status->id != submitted->id || status->name != mine.name) error = "wrong status";
          if (!files || files->paths.size() != 2 || !fs::exists(files->paths[0])) error = "fetch failed";
        }
        std::lock_guard lock(mutex);
        if (submitted) ids.insert(submitted->id);
        if (!error.empty()) errors.push_back(error);
      }
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_TRUE(errors.empty()) << ::testing::PrintToString(errors);
  EXPECT_EQ(ids.size(), static_cast<std::size_t>(kThreads * kJobsEach));
  // The server holds exactly these jobs: none lost, none twice.
  client::ListOptions all;
  all.limit = 500;
  const auto page = c.list(all);
  ASSERT_TRUE(page.ok()) << page.error().message;
  std::set<std::string> listed;
  for (const auto& s : page->jobs) listed.insert(s.id);
  EXPECT_EQ(listed, ids);
  EXPECT_EQ(requests_answered(server, {"route=\"/v1/jobs\"", "method=\"POST\""}), kThreads * kJobsEach);
  fs::remove_all(dir);
}

// StopSource and StopToken as std::stop_source and std::stop_token behave (WaitOptions::stop takes a StopToken, the
// client's headers being C++17).
TEST(SharedClient, StopTokenSeesItsSourcesRequestFromAnotherThread) {
  const client::StopToken none;
  EXPECT_FALSE(none.stop_possible());
  EXPECT_FALSE(none.stop_requested());

  client::StopToken kept;
  {
    client::StopSource source;
    const client::StopToken token = source.get_token();
    kept = token;
    EXPECT_TRUE(token.stop_possible());
    EXPECT_FALSE(token.stop_requested());
    EXPECT_FALSE(source.stop_requested());
    const client::StopSource copy = source;  // shares the state
    bool first = false;
    std::thread([&] { first = source.request_stop(); }).join();
    EXPECT_TRUE(first);
    EXPECT_FALSE(source.request_stop());  // made before
    EXPECT_TRUE(token.stop_requested());
    EXPECT_TRUE(copy.stop_requested());
    EXPECT_TRUE(copy.get_token().stop_requested());
    client::StopSource other;
    EXPECT_FALSE(other.get_token().stop_requested());  // a state of its own
  }
  EXPECT_TRUE(kept.stop_requested());  // the token outlives its source
}

TEST(SharedClient, WaitStopsWhenItsTokenIsRequested) {
  const fs::path dir = test_folder();
  ServerProcess server(dir / "data", {"--threads-per-job", "1"});
  client::Client c = client_for(server);
  const auto submitted = c.submit(proto::decode_job_spec(slow_image_job(600)));
  ASSERT_TRUE(submitted.ok()) << submitted.error().message;

  // Stopped before it starts: nothing is asked.
  client::StopSource early;
  early.request_stop();
  client::WaitOptions stopped;
  stopped.stop = early.get_token();
  EXPECT_EQ(c.wait(submitted->id, stopped).error().code, ErrorCode::kStopped);

  // Stopped from another thread while it waits: a long-poll (up to 30 s, answered only when the job's state
  // changes) is abandoned, so the wait ends while the job is still unfinished.
  client::StopSource source;
  client::WaitOptions options;
  options.stop = source.get_token();
  std::thread stopper([&] {
    const auto running = [&] {
      const auto s = c.status(submitted->id);  // the same Client, from a second thread
      return s.ok() && s->state == proto::JobState::kRunning;
    };
    while (!running()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the wait is in its long-poll by now
    source.request_stop();
  });
  const auto waited = c.wait(submitted->id, options);
  stopper.join();
  ASSERT_FALSE(waited.ok());
  EXPECT_EQ(waited.error().code, ErrorCode::kStopped);
  EXPECT_THAT(waited.error().message, HasSubstr("stopped"));
  const auto after = c.status(submitted->id);  // the Client still works, and the job was not touched
  ASSERT_TRUE(after.ok()) << after.error().message;
  EXPECT_FALSE(proto::is_terminal(after->state)) << proto::to_string(after->state);
  EXPECT_FALSE(after->cancel_requested);
  (void)c.cancel(submitted->id);
  fs::remove_all(dir);
}

TEST(ResultContract, ValueOrAndNoExceptions) {
  const client::Result<int> good = 5;
  const client::Result<int> bad = client::ClientError{ErrorCode::kHttp, 404, "not found", std::nullopt, std::nullopt};
  EXPECT_EQ(good.value_or(7), 5);
  EXPECT_EQ(bad.value_or(7), 7);
  EXPECT_EQ(client::Result<std::string>(std::string("x")).value_or("y"), "x");
  EXPECT_EQ(*good, 5);
  EXPECT_EQ(bad.error().http_status, 404);
  static_assert(noexcept(good.value())&& noexcept(good.error())&& noexcept(*good));
}

TEST(ResultContractDeathTest, ValueOfAnErrorAbortsWithTheMessage) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");  // the suite's other tests leave threads (servers' pipes)
  const client::Result<int> bad =
      client::ClientError{ErrorCode::kConnection, 0, "cannot connect to h:1", std::nullopt, std::nullopt};
  EXPECT_DEATH((void)bad.value(), "value\\(\\) of a failed Result: cannot connect to h:1 \\(connection\\)");
  const client::Result<int> good = 1;
  EXPECT_DEATH((void)good.error(), "error\\(\\) of a Result that holds a value");
}

TEST(JobJson, ParsesChecksAndRoundTrips) {
  const auto job = client::parse_job(image_job().dump());
  ASSERT_TRUE(job.ok()) << job.error().message;
  EXPECT_EQ(job.value(), proto::decode_job_spec(image_job()));  // what the codec reads
  const auto text = client::job_json(job.value());
  ASSERT_TRUE(text.ok());
  EXPECT_EQ(nlohmann::json::parse(text.value()), proto::encode_job_spec(job.value()));
  EXPECT_EQ(client::parse_job(text.value()).value(), job.value());

  nlohmann::json bad = image_job();
  bad["warp"]["features"][1]["target"] = "up";
  const auto refused = client::parse_job(bad.dump(), "scene.json");
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument);
  ASSERT_TRUE(refused.error().problem);
  EXPECT_EQ(refused.error().problem->path, "$.warp.features[1].target");
  EXPECT_THAT(refused.error().message, HasSubstr("$.warp.features[1].target"));
  const auto not_json = client::parse_job("{\"warp\": ", "scene.json");
  ASSERT_FALSE(not_json.ok());
  EXPECT_THAT(not_json.error().message, HasSubstr("scene.json"));
}

}  // namespace
}  // namespace texwarp::testing
