// libtexwarp_client's retries within a time budget: a wait that outlives a restart of the real texwarpd (SIGTERM,
// 5 s down, started again on the same port and data folder), giving up once the budget is spent with nobody
// listening, 4xx answers never retried (counted by the server's /metrics), and which answers are retried (a
// scripted peer).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <condition_variable>
#include <csignal>
#include <iostream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "client_test_support.hpp"
#include "raw_http.hpp"
#include "scripted_peer.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/client/client.hpp"
#include "texwarp/proto/job_spec_codec.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using client::Client;
using client::ClientOptions;
using client::ErrorCode;
using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// A loopback port nobody listens on: bound (so no other test takes it meanwhile) but never listened to.
class DeadPort {
 public:
  DeadPort() {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof addr;
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
      if (fd_ >= 0) ::close(fd_);
      throw std::runtime_error("DeadPort: cannot bind on loopback");
    }
    port_ = ntohs(addr.sin_port);
  }
  ~DeadPort() { ::close(fd_); }
  DeadPort(const DeadPort&) = delete;
  DeadPort& operator=(const DeadPort&) = delete;
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }

 private:
  int fd_ = -1;
  int port_ = 0;
};

class RetryBudget : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test_folder(); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// A job is running when texwarpd gets SIGTERM (with no grace, so the job goes back to the queue); 5 s later a new
// texwarpd starts on the same port and data folder and runs the job again. The wait started before the restart
// ends with the job succeeded.
TEST_F(RetryBudget, WaitOutlivesAServerRestart) {
  const std::vector<std::string> args = {"--threads-per-job", "1", "--workers", "1", "--shutdown-grace", "0"};
  auto server = std::make_unique<ServerProcess>(dir_ / "data", args);
  const unsigned short port = server->port();
  ClientOptions options;
  options.server = server->url();
  Client c(options);
  const auto submitted = c.submit(proto::decode_job_spec(slow_image_job(300)));
  ASSERT_TRUE(submitted.ok()) << submitted.error().message;

  std::mutex mutex;
  std::condition_variable changed;
  std::vector<proto::JobState> states;
  std::vector<Clock::time_point> seen_at;  // when the wait saw a change
  client::WaitOptions wait;
  wait.poll_max = std::chrono::milliseconds(100);
  wait.on_progress = [&](const proto::JobStatus& s) {
    std::lock_guard lock(mutex);
    if (states.empty() || states.back() != s.state) states.push_back(s.state);
    seen_at.push_back(Clock::now());
    changed.notify_all();
  };
  std::optional<client::Result<proto::JobStatus>> done;
  const auto wait_start = Clock::now();
  std::thread waiter([&] { done.emplace(c.wait(submitted->id, wait)); });

  bool running = false;
  {
    std::unique_lock lock(mutex);
    changed.wait_for(lock, std::chrono::seconds(60),
                     [&] { return !states.empty() && states.back() != proto::JobState::kQueued; });
    running = !states.empty() && states.back() == proto::JobState::kRunning;
  }
  if (!running) {
    server->signal(SIGKILL);
    waiter.join();
    FAIL() << "the job must be running when the server stops";
  }
  const auto stop = Clock::now();
  server->signal(SIGTERM);
  EXPECT_EQ(server->wait_exit(30), 0) << server->log();
  EXPECT_THAT(server->log(), HasSubstr("job interrupted by shutdown"));  // it did not finish before the restart
  std::this_thread::sleep_until(stop + std::chrono::seconds(5));         // the outage: nobody listens on the port
  server = std::make_unique<ServerProcess>(ListenPort{port}, dir_ / "data", args);
  const auto restarted = Clock::now();
  waiter.join();
  std::cout << "[ measure  ] Client::wait across the restart took " << seconds_since(wait_start)
            << " s: " << std::chrono::duration<double>(stop - wait_start).count() << " s until SIGTERM, "
            << std::chrono::duration<double>(restarted - stop).count() << " s until the new server listened, "
            << seconds_since(restarted) << " s more";
  const auto first_after = std::find_if(seen_at.begin(), seen_at.end(), [&](auto t) { return t >= restarted; });
  if (first_after != seen_at.end()) {
    std::cout << " (first change seen " << std::chrono::duration<double>(*first_after - restarted).count()
              << " s after the restart)";
  }
  std::cout << "\n";

  ASSERT_TRUE(done && done->ok()) << (done ? done->error().message : "no result");
  EXPECT_EQ(done->value().state, proto::JobState::kSucceeded);
  const auto fetched = c.fetch_results(submitted->id, (dir_ / "out").string());
  ASSERT_TRUE(fetched.ok()) << fetched.error().message;
  EXPECT_TRUE(fs::exists(dir_ / "out" / "warped.png"));
}

TEST_F(RetryBudget, NobodyListeningGivesUpWhenTheBudgetIsSpent) {
  DeadPort dead;
  ClientOptions options;
  options.server = dead.url();
  options.retry_budget = std::chrono::seconds(2);
  Client c(options);
  const auto start = Clock::now();
  const auto r = c.status("job_aaaaaaaaaaaaaaaaaaaaaaaaaa");
  const double spent_s = seconds_since(start);
  std::cout << "[ measure  ] a 2 s retry budget with nobody listening gave up after " << spent_s << " s\n";
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kConnection);
  EXPECT_THAT(r.error().message, HasSubstr("cannot connect"));
  EXPECT_THAT(r.error().message, HasSubstr("gave up after"));
  EXPECT_GE(spent_s, 2.0);
  EXPECT_LT(spent_s, 6.0);

  // A budget of 0 is a single attempt.
  options.retry_budget = std::chrono::milliseconds(0);
  const auto once_start = Clock::now();
  const auto once = Client(options).list();
  ASSERT_FALSE(once.ok());
  EXPECT_EQ(once.error().code, ErrorCode::kConnection);
  EXPECT_LT(seconds_since(once_start), 1.0);
}

TEST_F(RetryBudget, TheWaitTimeoutWinsOverTheBudget) {
  DeadPort dead;
  ClientOptions options;
  options.server = dead.url();
  Client c(options);  // the 60 s default budget
  client::WaitOptions wait;
  wait.timeout = std::chrono::milliseconds(1500);
  const auto start = Clock::now();
  const auto r = c.wait("job_aaaaaaaaaaaaaaaaaaaaaaaaaa", wait);
  const double spent_s = seconds_since(start);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kTimeout) << r.error().message;
  EXPECT_THAT(r.error().message, HasSubstr("before the wait timeout"));
  EXPECT_GE(spent_s, 1.5);
  EXPECT_LT(spent_s, 5.0);
}

TEST_F(RetryBudget, NegativeSettingsAreRefused) {
  ClientOptions options;
  options.retry_budget = std::chrono::milliseconds(-1);
  const auto r = Client(options).list();
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
  EXPECT_THAT(r.error().message, HasSubstr("retry_budget"));
  ClientOptions hot;  // no pause at all between retries would hammer the server for the whole budget
  hot.max_retry_delay = std::chrono::milliseconds(0);
  const auto h = Client(hot).list();
  ASSERT_FALSE(h.ok());
  EXPECT_EQ(h.error().code, ErrorCode::kInvalidArgument);
  EXPECT_THAT(h.error().message, HasSubstr("max_retry_delay"));
}

TEST_F(RetryBudget, FourHundredsAreNotRetried) {
  ServerProcess server(dir_ / "data");
  ClientOptions options;
  options.server = server.url();
  options.initial_backoff = std::chrono::milliseconds(1);
  Client c(options);

  const long not_found_before = requests_answered(server, {"status=\"404\""});
  const auto unknown = c.status("job_aaaaaaaaaaaaaaaaaaaaaaaaaa");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().http_status, 404);
  EXPECT_EQ(requests_answered(server, {"status=\"404\""}), not_found_before + 1);

  nlohmann::json bad = image_job();
  bad["warp"]["tolerance_px"] = -1;
  const long invalid_before = requests_answered(server, {"status=\"422\""});
  const auto refused = c.submit_json(bad.dump());
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().http_status, 422);
  EXPECT_EQ(requests_answered(server, {"status=\"422\""}), invalid_before + 1);
}

const std::string kEmptyPage = R"({"jobs": [], "next_cursor": null})";

TEST(RetryAnswers, GatewayErrorsAndBusyAreRetriedOtherFourHundredsNot) {
  ScriptedPeer peer({scripted_reply(502), scripted_reply(504), scripted_reply(503), scripted_reply(429),
                     scripted_reply(200, "", kEmptyPage)});
  ClientOptions options;
  options.server = peer.url();
  options.initial_backoff = std::chrono::milliseconds(5);
  const auto listed = Client(options).list();
  ASSERT_TRUE(listed.ok()) << listed.error().message;
  EXPECT_EQ(peer.requests(), 5);

  for (const int status : {400, 401, 403, 404, 409, 413, 422}) {
    ScriptedPeer refusing({scripted_reply(status), scripted_reply(200, "", kEmptyPage)});
    options.server = refusing.url();
    const auto r = Client(options).list();
    ASSERT_FALSE(r.ok()) << status;
    EXPECT_EQ(r.error().http_status, status);
    EXPECT_EQ(refusing.requests(), 1) << status;
  }
}

TEST(RetryAnswers, ARetryAfterBeyondTheBudgetEndsTheCallAtOnce) {
  ScriptedPeer peer({scripted_reply(503, "Retry-After: 3\r\n"), scripted_reply(200, "", kEmptyPage)});
  ClientOptions options;
  options.server = peer.url();
  options.retry_budget = std::chrono::seconds(1);
  const auto start = Clock::now();
  const auto r = Client(options).list();
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().http_status, 503);
  EXPECT_EQ(peer.requests(), 1);
  EXPECT_LT(seconds_since(start), 2.5);  // not the 3 s it asked for
}

// The server's Retry-After is honoured as given, not cut to the client's own backoff cap (which would ask an
// overloaded server again sooner than it said).
TEST(RetryAnswers, ARetryAfterIsWaitedForInFullWithinTheBudget) {
  ScriptedPeer peer({scripted_reply(429, "Retry-After: 1\r\n"), scripted_reply(200, "", kEmptyPage)});
  ClientOptions options;
  options.server = peer.url();
  options.max_retry_delay = std::chrono::milliseconds(100);
  options.retry_budget = std::chrono::seconds(10);
  const auto r = Client(options).list();
  ASSERT_TRUE(r.ok()) << r.error().message;
  const auto arrivals = peer.arrivals();
  ASSERT_EQ(arrivals.size(), 2u);
  EXPECT_GE(arrivals[1] - arrivals[0], std::chrono::milliseconds(990));
}

}  // namespace
}  // namespace texwarp::testing
