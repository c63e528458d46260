// libtexwarp_client's farm-queue calls against the real texwarpd: priority and labels round trip, batches (all or
// none, the refused job named), list filters with hostile label values, long-poll waits (their requests counted by
// the server's /metrics), purge against cancel, nodes; and a wait's fallback to polling against scripted servers
// that refuse or ignore ?wait.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <ctime>
#include <iostream>
#include <set>
#include <sstream>

#include "client_test_support.hpp"
#include "raw_http.hpp"
#include "scripted_peer.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/client/client.hpp"
#include "texwarp/proto/job_batch.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using client::Client;
using client::ClientOptions;
using client::ErrorCode;
using ::testing::HasSubstr;
using ::testing::StartsWith;
using Clock = std::chrono::steady_clock;

proto::JobSpec named_job(const std::string& name) {
  proto::JobSpec job = proto::decode_job_spec(image_job());
  job.name = name;
  return job;
}

// An RFC 3339 UTC time with milliseconds ("2026-11-30T19:07:22.123Z") as a system_clock time point.
std::chrono::system_clock::time_point parse_utc(const std::string& text) {
  std::tm tm{};
  const char* rest = strptime(text.c_str(), "%Y-%m-%dT%H:%M:%S", &tm);
  EXPECT_NE(rest, nullptr) << text;
  double fraction = 0.0;
  if (rest && *rest == '.') fraction = std::stod("0" + std::string(rest, std::strcspn(rest, "Z")));
  return std::chrono::system_clock::from_time_t(timegm(&tm)) +
         std::chrono::duration_cast<std::chrono::system_clock::duration>(std::chrono::duration<double>(fraction));
}

std::set<std::string> ids_of(const proto::JobPage& page) {
  std::set<std::string> ids;
  for (const auto& j : page.jobs) ids.insert(j.id);
  return ids;
}

class ClientQueue : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test_folder(); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ClientQueue, PriorityAndLabelsRoundTrip) {
  ServerProcess server(dir_ / "data");
  Client c = client_for(server);
  proto::JobSpec job = named_job("tagged");
  job.priority = -7;
  job.labels = {{"shot", "sq010/sh0040"}, {"artist", "Zoë & co = 1+1"}, {"empty", ""}};
  const auto submitted = c.submit(job);
  ASSERT_TRUE(submitted.ok()) << submitted.error().message;
  EXPECT_EQ(submitted->priority, -7);
  EXPECT_EQ(submitted->labels, job.labels);
  const auto done = c.wait(submitted->id);
  ASSERT_TRUE(done.ok()) << done.error().message;
  EXPECT_EQ(done->state, proto::JobState::kSucceeded);
  EXPECT_EQ(done->priority, -7);
  EXPECT_EQ(done->labels, job.labels);
  const auto nodes = c.nodes();
  ASSERT_TRUE(nodes.ok()) << nodes.error().message;
  ASSERT_EQ(nodes->nodes.size(), 1u);
  EXPECT_EQ(done->node, nodes->nodes[0].id);  // the node that ran it
}

TEST_F(ClientQueue, ABatchIsAcceptedWholeInOrderAndReplayedByItsKey) {
  ServerProcess server(dir_ / "data", {"--workers", "1"});
  Client c = client_for(server);
  std::vector<proto::JobSpec> jobs = {named_job("first"), named_job("second"), named_job("third")};
  jobs[2].priority = 9;
  jobs[1].labels = {{"batch", "b1"}};
  const auto submitted = c.submit_batch(jobs, "batch-key-1");
  ASSERT_TRUE(submitted.ok()) << submitted.error().message;
  ASSERT_EQ(submitted->size(), 3u);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    EXPECT_EQ(submitted.value()[i].name, jobs[i].name);
    EXPECT_EQ(submitted.value()[i].priority, jobs[i].priority);
    EXPECT_EQ(submitted.value()[i].labels, jobs[i].labels);
    const auto s = c.status(submitted.value()[i].id);
    ASSERT_TRUE(s.ok()) << s.error().message;
    EXPECT_EQ(s->name, jobs[i].name);
  }
  EXPECT_EQ(std::set<std::string>({submitted.value()[0].id, submitted.value()[1].id, submitted.value()[2].id}).size(),
            3u);
  // The same key and body again: the same jobs, none added.
  const auto again = c.submit_batch(jobs, "batch-key-1");
  ASSERT_TRUE(again.ok()) << again.error().message;
  for (std::size_t i = 0; i < jobs.size(); ++i) EXPECT_EQ(again.value()[i].id, submitted.value()[i].id);
  const auto all = c.list();
  ASSERT_TRUE(all.ok()) << all.error().message;
  EXPECT_EQ(all->jobs.size(), 3u);
  // Two pages through the cursor (sent escaped): every job once.
  client::ListOptions paging;
  paging.limit = 2;
  const auto first = c.list(paging);
  ASSERT_TRUE(first.ok()) << first.error().message;
  ASSERT_EQ(first->jobs.size(), 2u);
  ASSERT_FALSE(first->next_cursor.empty());
  paging.cursor = first->next_cursor;
  const auto second = c.list(paging);
  ASSERT_TRUE(second.ok()) << second.error().message;
  ASSERT_EQ(second->jobs.size(), 1u);
  std::set<std::string> paged = ids_of(first.value());
  paged.insert(second->jobs[0].id);
  EXPECT_EQ(paged, ids_of(all.value()));
}

TEST_F(ClientQueue, ABatchWithOneInvalidJobIsRefusedWholeAndNamesIt) {
  ServerProcess server(dir_ / "data");
  Client c = client_for(server);
  std::vector<proto::JobSpec> jobs = {named_job("ok-0"), named_job("bad-1"), named_job("ok-2")};
  jobs[1].priority = 5000;  // the encoder writes it; the server's decoder refuses it
  const auto refused = c.submit_batch(jobs);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kHttp);
  EXPECT_EQ(refused.error().http_status, 422);
  ASSERT_TRUE(refused.error().batch_index);
  EXPECT_EQ(*refused.error().batch_index, 1u);
  ASSERT_TRUE(refused.error().problem);
  EXPECT_THAT(refused.error().problem->path, StartsWith("$.jobs[1]"));
  EXPECT_THAT(refused.error().message, HasSubstr("job 1 of 3 refused, nothing was submitted"));
  EXPECT_THAT(refused.error().message, HasSubstr("priority"));
  const auto all = c.list();
  ASSERT_TRUE(all.ok()) << all.error().message;
  EXPECT_TRUE(all->jobs.empty());  // nothing stored

  // Refused here, before anything is sent.
  EXPECT_EQ(c.submit_batch({}).error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(c.submit_batch(std::vector<proto::JobSpec>(proto::kMaxBatchJobs + 1, named_job("x"))).error().code,
            ErrorCode::kInvalidArgument);
}

TEST_F(ClientQueue, ListFiltersByLabelsWithHostileCharacters) {
  ServerProcess server(dir_ / "data");
  Client c = client_for(server);
  const std::string ampersand = "a&b=c d";
  const std::string unicode = "ü 東京 + %20 #x";
  std::vector<proto::JobSpec> jobs = {named_job("j0"), named_job("j1"), named_job("j2"), named_job("j3")};
  jobs[0].labels = {{"team", ampersand}, {"dept/fx.v-2", "x"}};
  jobs[1].labels = {{"team", unicode}};
  jobs[2].labels = {{"team", "a"}};
  jobs[3].labels = {{"team", ampersand}};
  const auto submitted = c.submit_batch(jobs);
  ASSERT_TRUE(submitted.ok()) << submitted.error().message;
  const auto id = [&](int i) { return submitted.value()[static_cast<std::size_t>(i)].id; };

  const auto list = [&](proto::JobLabels labels) {
    client::ListOptions options;
    options.labels = std::move(labels);
    const auto page = c.list(options);
    EXPECT_TRUE(page.ok()) << page.error().message;
    return page.ok() ? ids_of(page.value()) : std::set<std::string>{};
  };
  EXPECT_EQ(list({{"team", ampersand}}), (std::set<std::string>{id(0), id(3)}));
  EXPECT_EQ(list({{"team", ampersand}, {"dept/fx.v-2", "x"}}), (std::set<std::string>{id(0)}));  // AND-ed
  EXPECT_EQ(list({{"team", unicode}}), (std::set<std::string>{id(1)}));
  EXPECT_EQ(list({{"team", "a"}}), (std::set<std::string>{id(2)}));  // not a prefix of "a&b=c d"
  EXPECT_EQ(list({{"team", "a&b"}}), (std::set<std::string>{}));
  EXPECT_EQ(list({{"team", ""}}), (std::set<std::string>{}));
  EXPECT_EQ(list({{"dept/fx.v-2", "x"}, {"team", "a"}}), (std::set<std::string>{}));

  // A filter no job could carry is refused before it is sent.
  client::ListOptions bad;
  bad.labels = {{"bad key", "v"}};
  EXPECT_EQ(c.list(bad).error().code, ErrorCode::kInvalidArgument);
  bad.labels = {{"k", "\xff"}};
  EXPECT_THAT(c.list(bad).error().message, HasSubstr("UTF-8"));
}

// A job of about 2 s (300² pixel by pixel on one thread): the long-poll asks a handful of times where polling
// every 200 ms would ask ~10 times, and it returns at the change, not at the end of its 30 s.
TEST_F(ClientQueue, LongPollWaitReturnsAtTheChangeWithFewRequests) {
  ServerProcess server(dir_ / "data", {"--threads-per-job", "1", "--workers", "1"});
  Client c = client_for(server);
  const auto submitted = c.submit(proto::decode_job_spec(slow_image_job(300)));
  ASSERT_TRUE(submitted.ok()) << submitted.error().message;
  const long before = requests_answered(server, {"route=\"/v1/jobs/{id}\"", "method=\"GET\""});
  const auto start = Clock::now();
  const auto done = c.wait(submitted->id);
  const auto returned_at = std::chrono::system_clock::now();
  const double waited_s = std::chrono::duration<double>(Clock::now() - start).count();
  ASSERT_TRUE(done.ok()) << done.error().message;
  ASSERT_EQ(done->state, proto::JobState::kSucceeded);
  const long requests = requests_answered(server, {"route=\"/v1/jobs/{id}\"", "method=\"GET\""}) - before;
  const double lag_s = std::chrono::duration<double>(returned_at - parse_utc(done->finished_at)).count();
  const double run_s =
      std::chrono::duration<double>(parse_utc(done->finished_at) - parse_utc(done->started_at)).count();
  std::cout << "[ measure  ] long-poll wait of " << waited_s << " s (job ran " << run_s << " s): " << requests
            << " GET /v1/jobs/{id} requests (polling every 200 ms: " << static_cast<int>(waited_s / 0.2)
            << "); returned " << lag_s << " s after the job finished\n";
  // One look, one long-poll per change of state (queued → running → succeeded), and one more for each long-poll
  // that ran its whole kMaxLongPollS without a change (a job slower than that: under ThreadSanitizer, 6 requests).
  EXPECT_GE(requests, 2);
  EXPECT_LE(requests, 4 + static_cast<long>(run_s / client::kMaxLongPollS));
  EXPECT_LT(static_cast<double>(requests), waited_s / 0.2);
  EXPECT_LT(lag_s, 5.0);  // at the change, not at the long-poll's 30 s

  // With a progress callback the job is asked about every second, and each change is reported once.
  const auto second = c.submit(proto::decode_job_spec(slow_image_job(300)));
  ASSERT_TRUE(second.ok()) << second.error().message;
  std::vector<proto::JobStatus> seen;
  client::WaitOptions options;
  options.on_progress = [&](const proto::JobStatus& s) { seen.push_back(s); };
  const auto done2 = c.wait(second->id, options);
  ASSERT_TRUE(done2.ok()) << done2.error().message;
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back().state, proto::JobState::kSucceeded);
  EXPECT_EQ(seen.back().progress, 100);
  for (std::size_t i = 1; i < seen.size(); ++i) {
    EXPECT_TRUE(seen[i].state != seen[i - 1].state || seen[i].progress != seen[i - 1].progress);
    EXPECT_GE(seen[i].progress, seen[i - 1].progress);
  }
}

TEST_F(ClientQueue, PurgeDeletesAFinishedJobAndCancelKeepsToUnfinishedOnes) {
  ServerProcess server(dir_ / "data", {"--threads-per-job", "1", "--workers", "1"});
  Client c = client_for(server);
  const auto fetched = c.run(named_job("done"), (dir_ / "out").string());
  ASSERT_TRUE(fetched.ok()) << fetched.error().message;
  const std::string id = fetched->result.job_id;
  const auto results_of = [&] {
    int folders = 0;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(server.data_dir() / "results", ec)) {
      if (e.path().filename().string().find(id) != std::string::npos) ++folders;
    }
    return folders;
  };
  EXPECT_EQ(results_of(), 1);

  // cancel() leaves a finished job alone: the server answers POST …:cancel with 409 job-finished and keeps the job,
  // its result and its files (a DELETE would have purged them).
  const auto not_canceled = c.cancel(id);
  ASSERT_FALSE(not_canceled.ok());
  EXPECT_EQ(not_canceled.error().code, ErrorCode::kWrongState);
  EXPECT_EQ(not_canceled.error().http_status, 409);
  ASSERT_TRUE(not_canceled.error().problem.has_value());
  EXPECT_EQ(not_canceled.error().problem->type, "urn:texwarp:problem:job-finished");
  EXPECT_THAT(not_canceled.error().message, HasSubstr("already finished (succeeded)"));
  const auto kept = c.status(id);
  ASSERT_TRUE(kept.ok()) << kept.error().message;
  EXPECT_EQ(kept->state, proto::JobState::kSucceeded);
  const auto kept_result = c.result(id);
  ASSERT_TRUE(kept_result.ok()) << kept_result.error().message;
  EXPECT_EQ(kept_result->files.size(), fetched->result.files.size());
  EXPECT_EQ(results_of(), 1);

  const auto purged = c.purge(id);
  ASSERT_TRUE(purged.ok()) << purged.error().message;
  EXPECT_EQ(c.status(id).error().http_status, 404);
  EXPECT_EQ(c.result(id).error().http_status, 404);
  EXPECT_EQ(results_of(), 0);  // its files went with it
  EXPECT_EQ(c.purge(id).error().http_status, 404);

  // purge() leaves an unfinished job alone; cancel() stops it, then it can be purged.
  const auto slow = c.submit(proto::decode_job_spec(slow_image_job(600)));
  ASSERT_TRUE(slow.ok()) << slow.error().message;
  const auto not_purged = c.purge(slow->id);
  ASSERT_FALSE(not_purged.ok());
  EXPECT_EQ(not_purged.error().code, ErrorCode::kWrongState);
  EXPECT_THAT(not_purged.error().message, HasSubstr("only a finished job can be purged"));
  const auto still = c.status(slow->id);
  ASSERT_TRUE(still.ok());
  EXPECT_FALSE(still->cancel_requested);
  EXPECT_FALSE(proto::is_terminal(still->state));
  ASSERT_TRUE(c.cancel(slow->id).ok());
  const auto canceled = c.wait(slow->id);
  ASSERT_TRUE(canceled.ok());
  EXPECT_EQ(canceled->state, proto::JobState::kCanceled);
  EXPECT_TRUE(c.purge(slow->id).ok());
  EXPECT_EQ(c.status(slow->id).error().http_status, 404);
}

TEST_F(ClientQueue, NodesListsTheOneNode) {
  ServerProcess server(dir_ / "data", {"--workers", "2"});
  Client c = client_for(server);
  const auto nodes = c.nodes();
  ASSERT_TRUE(nodes.ok()) << nodes.error().message;
  ASSERT_EQ(nodes->nodes.size(), 1u);
  const proto::NodeStatus& node = nodes->nodes[0];
  EXPECT_TRUE(node.alive);
  EXPECT_EQ(node.pid, server.pid());
  EXPECT_EQ(node.workers, 2);
  EXPECT_EQ(node.running, 0);
  EXPECT_THAT(node.id, HasSubstr(":" + std::to_string(server.port())));
  EXPECT_FALSE(node.version.empty());
  EXPECT_FALSE(node.last_seen_at.empty());
}

std::string status_reply(proto::JobState state, int progress) {
  proto::JobStatus s;
  s.id = "job_x";
  s.state = state;
  s.progress = progress;
  s.created_at = "2026-01-01T00:00:00.000Z";
  return scripted_reply(200, "Content-Type: application/json\r\n", proto::encode_job_status(s).dump());
}

// An older server answers 400 to ?wait: the wait asks again without it and polls from then on.
TEST(ClientWaitFallback, PollsAServerThatRefusesWait) {
  ScriptedPeer peer({status_reply(proto::JobState::kRunning, 10),
                     scripted_reply(400, "Content-Type: application/problem+json\r\n",
                                    R"({"type": "urn:texwarp:problem:bad-query", "status": 400})"),
                     status_reply(proto::JobState::kRunning, 20), status_reply(proto::JobState::kRunning, 30),
                     status_reply(proto::JobState::kSucceeded, 100)});
  ClientOptions options;
  options.server = peer.url();
  Client c(options);
  client::WaitOptions wait;
  wait.poll_min = std::chrono::milliseconds(50);
  const auto done = c.wait("job_x", wait);
  ASSERT_TRUE(done.ok()) << done.error().message;
  EXPECT_EQ(done->state, proto::JobState::kSucceeded);
  const auto lines = peer.request_lines();
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0], "GET /v1/jobs/job_x HTTP/1.1");
  EXPECT_EQ(lines[1], "GET /v1/jobs/job_x?wait=30 HTTP/1.1");
  for (std::size_t i = 2; i < lines.size(); ++i) EXPECT_EQ(lines[i], "GET /v1/jobs/job_x HTTP/1.1");
  const auto at = peer.arrivals();
  EXPECT_GE(at[3] - at[2], std::chrono::milliseconds(50));  // polling pauses again
  EXPECT_GE(at[4] - at[3], std::chrono::milliseconds(75));
}

// A server that ignores ?wait answers at once: the wait pauses between requests as polling does (no busy loop),
// and a long-poll never asks for more than the wait's time left.
TEST(ClientWaitFallback, NoBusyLoopWhenAServerIgnoresWait) {
  std::vector<std::string> replies(6, status_reply(proto::JobState::kQueued, 0));
  replies.push_back(status_reply(proto::JobState::kSucceeded, 100));
  ScriptedPeer peer(replies);
  ClientOptions options;
  options.server = peer.url();
  Client c(options);
  client::WaitOptions wait;
  wait.poll_min = std::chrono::milliseconds(40);
  wait.timeout = std::chrono::seconds(20);
  const auto done = c.wait("job_x", wait);
  ASSERT_TRUE(done.ok()) << done.error().message;
  const auto lines = peer.request_lines();
  ASSERT_EQ(lines.size(), 7u);
  EXPECT_THAT(lines[1], HasSubstr("?wait=19 "));  // within the 20 s timeout, in whole seconds
  const auto at = peer.arrivals();
  for (std::size_t i = 2; i < at.size(); ++i) EXPECT_GE(at[i] - at[i - 1], std::chrono::milliseconds(40)) << i;
}

}  // namespace
}  // namespace texwarp::testing
