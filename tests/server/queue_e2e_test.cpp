// The farm queue's routes through the real texwarpd (SQLite, one node): priority order, label filters, batch
// submission all or none (a batch larger than the queue refused, not told to retry), replays answered while the queue
// is full, purge of finished jobs, a cancel that never purges, long polls (answered at the change or at the deadline,
// and 64 of them waiting starve nobody), GET /v1/nodes, the node metrics, an honest Retry-After on a young server, and
// the new flags' checks.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

#include "api_helpers.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

class QueueE2E : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test_folder(); }
  void TearDown() override {
    server_.reset();
    fs::remove_all(dir_);
  }
  ServerProcess& start(std::vector<std::string> args = {}) {
    args.insert(args.end(), {"--threads-per-job", "1"});
    server_ = std::make_unique<ServerProcess>(dir_ / "data", std::move(args));
    return *server_;
  }
  unsigned short port() const { return server_->port(); }
  // Occupies the single worker with a slow job until release() (so that what is submitted next stays queued).
  void hold_worker() {
    held_ = submit_job(port(), slow_image_job(600)).json()["id"];
    wait_for_state(port(), held_, "running", 30);
  }
  void release() { EXPECT_EQ(http_request(port(), "DELETE", "/v1/jobs/" + held_).status, 202); }
  std::string submit(const nlohmann::json& job, const Headers& headers = {}) {
    const HttpReply r = submit_job(port(), job, headers);
    EXPECT_EQ(r.status, 202) << r.body;
    return r.json().value("id", "");
  }
  std::vector<std::string> listed(const std::string& query) {
    const HttpReply r = http_request(port(), "GET", "/v1/jobs" + query);
    EXPECT_EQ(r.status, 200) << r.body;
    const nlohmann::json page = r.json();  // kept: a range-for over r.json()["jobs"] would outlive the parsed value
    std::vector<std::string> ids;
    for (const auto& j : page["jobs"]) ids.push_back(j["id"]);
    return ids;
  }
  HttpReply batch(const nlohmann::json& jobs, const Headers& headers = {}) {
    return http_request(port(), "POST", "/v1/jobs:batch", nlohmann::json{{"jobs", jobs}}.dump(), headers);
  }

  fs::path dir_;
  std::unique_ptr<ServerProcess> server_;
  std::string held_;
};

nlohmann::json with(nlohmann::json job, int priority, nlohmann::json labels = nlohmann::json::object()) {
  job["priority"] = priority;
  job["labels"] = std::move(labels);
  return job;
}

TEST_F(QueueE2E, HigherPriorityRunsFirstAndFifoWithin) {
  start();
  hold_worker();
  const std::vector<int> priorities = {0, 5, -3, 5, 10, 0};
  std::vector<std::string> ids;
  ids.reserve(priorities.size());
  for (int p : priorities) ids.push_back(submit(with(image_job(), p)));
  release();
  std::vector<std::pair<std::string, std::string>> started;  // started_at, id
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const nlohmann::json s = wait_for_job(port(), ids[i]);
    ASSERT_EQ(s["state"], "succeeded") << s.dump();
    EXPECT_EQ(s["priority"], priorities[i]);
    started.emplace_back(s["started_at"], ids[i]);
  }
  std::sort(started.begin(), started.end());
  // 10, then the two 5s in submission order, the two 0s in submission order, then -3.
  const std::vector<std::string> expected = {ids[4], ids[1], ids[3], ids[0], ids[5], ids[2]};
  std::vector<std::string> order;
  order.reserve(started.size());
  for (const auto& [t, id] : started) order.push_back(id);
  EXPECT_EQ(order, expected);
}

TEST_F(QueueE2E, ListsFilterOnLabelsAllOfThem) {
  start();
  hold_worker();
  const std::string a = submit(with(image_job(), 0, {{"shot", "sh010"}, {"dept", "paint"}}));
  const std::string b = submit(with(image_job(), 0, {{"shot", "sh010"}, {"dept", "lookdev"}}));
  const std::string c = submit(with(image_job(), 0, {{"shot", "sh020"}}));
  EXPECT_EQ(listed("?label=shot=sh010"), (std::vector<std::string>{b, a}));  // newest first
  EXPECT_EQ(listed("?label=shot=sh010&label=dept=paint"), (std::vector<std::string>{a}));
  EXPECT_EQ(listed("?label=shot=sh020&state=queued"), (std::vector<std::string>{c}));
  EXPECT_EQ(listed("?label=shot=sh020&state=running"), (std::vector<std::string>{}));
  EXPECT_EQ(listed("?label=shot%3Dsh010&label=dept=lookdev&limit=1"), (std::vector<std::string>{b}));
  const nlohmann::json status = job_status(port(), a);
  EXPECT_EQ(status["labels"], (nlohmann::json{{"dept", "paint"}, {"shot", "sh010"}}));
  for (const char* bad : {"?label=shot", "?label=sh%20ot=x", "?label==x", "?label=a=1&label=a=2"}) {
    const HttpReply r = http_request(port(), "GET", std::string("/v1/jobs") + bad);
    EXPECT_TRUE(is_problem(r, 400, "bad-query")) << bad << ": " << r.body;
    EXPECT_EQ(r.json().value("path", ""), "?label") << bad;
  }
  release();
}

TEST_F(QueueE2E, ABatchIsAcceptedInOrderOrNotAtAll) {
  start();
  hold_worker();
  const std::size_t before = listed("?limit=500").size();
  nlohmann::json jobs = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) {
    nlohmann::json j = with(image_job(), i, {{"i", std::to_string(i)}});
    j["name"] = "batch-" + std::to_string(i);
    jobs.push_back(j);
  }
  // One invalid job: 422 naming it, nothing stored.
  nlohmann::json bad = jobs;
  bad[2]["warp"]["features"][1]["source"] = "here";
  const HttpReply refused = batch(bad);
  EXPECT_TRUE(is_problem(refused, 422, "invalid-job")) << refused.body;
  EXPECT_EQ(refused.json().value("path", ""), "$.jobs[2].warp.features[1].source");
  bad = jobs;
  bad[1]["image"] = {{"blob", "sha256:" + std::string(64, '0')}};  // valid JSON, but no such blob (server-side check)
  const HttpReply unknown_blob = batch(bad);
  EXPECT_TRUE(is_problem(unknown_blob, 422, "invalid-job")) << unknown_blob.body;
  EXPECT_EQ(unknown_blob.json().value("path", "").rfind("$.jobs[1].image", 0), 0u) << unknown_blob.body;
  EXPECT_TRUE(is_problem(batch(nlohmann::json::array()), 422, "invalid-job"));
  EXPECT_TRUE(is_problem(http_request(port(), "POST", "/v1/jobs:batch", "{\"jobs\": ["), 400, "malformed-json"));
  EXPECT_EQ(listed("?limit=500").size(), before);

  // Valid: 201 with every status in the batch's order.
  const Headers key = {{"Idempotency-Key", "batch-key-1"}};
  const HttpReply accepted = batch(jobs, key);
  ASSERT_EQ(accepted.status, 201) << accepted.body;
  const nlohmann::json answer = accepted.json();
  ASSERT_EQ(answer["jobs"].size(), 3u);
  std::vector<std::string> ids;
  for (int i = 0; i < 3; ++i) {
    const auto& s = answer["jobs"][static_cast<std::size_t>(i)];
    EXPECT_EQ(s["name"], "batch-" + std::to_string(i));
    EXPECT_EQ(s["priority"], i);
    EXPECT_EQ(s["state"], "queued");
    ids.push_back(s["id"]);
  }
  EXPECT_EQ(listed("?limit=500").size(), before + 3);
  // The same key and body again: the same jobs, replayed; another body with the key: 422.
  const HttpReply replay = batch(jobs, key);
  ASSERT_EQ(replay.status, 201) << replay.body;
  EXPECT_EQ(replay.header("idempotent-replayed"), "true");
  for (int i = 0; i < 3; ++i) EXPECT_EQ(replay.json()["jobs"][static_cast<std::size_t>(i)]["id"], ids[i]);
  nlohmann::json other = jobs;
  other[1]["name"] = "changed";
  EXPECT_TRUE(is_problem(batch(other, key), 422, "idempotency-key-reused"));
  EXPECT_EQ(listed("?limit=500").size(), before + 3);
  release();
  for (const auto& id : ids) EXPECT_EQ(wait_for_job(port(), id)["state"], "succeeded");
}

// A batch larger than the whole queue can never be accepted: 422 naming $.jobs, not a 429 that a client would retry
// until its budget runs out (the client library and the CLI retry 429).
TEST_F(QueueE2E, ABatchLargerThanTheQueueIsRefusedNotToldToRetry) {
  start({"--max-queue", "2"});
  const nlohmann::json three = nlohmann::json::array({image_job(), image_job(), image_job()});
  const HttpReply refused = batch(three);
  EXPECT_TRUE(is_problem(refused, 422, "invalid-job")) << refused.body;
  EXPECT_EQ(refused.json().value("path", ""), "$.jobs");
  EXPECT_THAT(refused.json().value("detail", ""), HasSubstr("at most 2"));
  EXPECT_EQ(refused.header("retry-after"), "");
  EXPECT_TRUE(listed("").empty());
  const HttpReply two = batch(nlohmann::json::array({image_job(), image_job()}));
  EXPECT_EQ(two.status, 201) << two.body;
}

TEST_F(QueueE2E, AReplayIsAnsweredWhileTheQueueIsFullAndAReusedBatchKeyStoresNothing) {
  start({"--max-queue", "3"});
  hold_worker();
  nlohmann::json a = image_job();
  a["name"] = "a";
  nlohmann::json b = image_job();
  b["name"] = "b";
  const HttpReply first_batch = batch(nlohmann::json::array({a}), {{"Idempotency-Key", "kb"}});
  ASSERT_EQ(first_batch.status, 201) << first_batch.body;
  const std::string batched = first_batch.json()["jobs"][0]["id"];
  // Job 0's key was used with another body: 422 naming it, and job 1 (new, and there is room for it) is not stored
  // either.
  nlohmann::json changed = a;
  changed["name"] = "a2";
  const HttpReply reused = batch(nlohmann::json::array({changed, b}), {{"Idempotency-Key", "kb"}});
  EXPECT_TRUE(is_problem(reused, 422, "idempotency-key-reused")) << reused.body;
  EXPECT_EQ(reused.json().value("path", ""), "$.jobs[0]");
  EXPECT_EQ(listed("?state=queued"), std::vector<std::string>{batched});

  const std::string single = submit(a, {{"Idempotency-Key", "ks"}});
  const std::string plain = submit(b);  // the queue is full now
  ASSERT_TRUE(is_problem(submit_job(port(), b), 429, "queue-full"));
  // Replays are not new work: the original jobs, not 429.
  const HttpReply again = submit_job(port(), a, {{"Idempotency-Key", "ks"}});
  EXPECT_EQ(again.status, 202) << again.body;
  EXPECT_EQ(again.header("idempotent-replayed"), "true");
  EXPECT_EQ(again.json().value("id", ""), single);
  const HttpReply batch_again = batch(nlohmann::json::array({a}), {{"Idempotency-Key", "kb"}});
  ASSERT_EQ(batch_again.status, 201) << batch_again.body;
  EXPECT_EQ(batch_again.header("idempotent-replayed"), "true");
  EXPECT_EQ(batch_again.json()["jobs"].size(), 1u);
  EXPECT_EQ(batch_again.json()["jobs"][0]["id"], batched);
  // Another body under a stored key is refused as such, full queue or not.
  EXPECT_TRUE(is_problem(submit_job(port(), b, {{"Idempotency-Key", "ks"}}), 422, "idempotency-key-reused"));
  EXPECT_TRUE(
      is_problem(batch(nlohmann::json::array({b}), {{"Idempotency-Key", "kb"}}), 422, "idempotency-key-reused"));
  EXPECT_EQ(listed("?state=queued").size(), 3u);
  release();
  EXPECT_EQ(wait_for_job(port(), plain)["state"], "succeeded");
  EXPECT_EQ(wait_for_job(port(), single)["state"], "succeeded");
  EXPECT_EQ(wait_for_job(port(), batched)["state"], "succeeded");
}

// A single job sent with the key "z#0" and a batch sent with "z" are different requests: the batch's job 0 is new,
// never the single job (they shared the stored key "z#0" once).
TEST_F(QueueE2E, ABatchKeyNeverMeetsASingleJobsKey) {
  start();
  nlohmann::json single = image_job();
  single["name"] = "single";
  const std::string single_id = submit(single, {{"Idempotency-Key", "z#0"}});
  nlohmann::json first = image_job();
  first["name"] = "batch-0";
  const HttpReply accepted = batch(nlohmann::json::array({first, image_job()}), {{"Idempotency-Key", "z"}});
  ASSERT_EQ(accepted.status, 201) << accepted.body;
  EXPECT_EQ(accepted.header("idempotent-replayed"), "");
  EXPECT_NE(accepted.json()["jobs"][0]["id"], single_id);
  EXPECT_EQ(accepted.json()["jobs"][0]["name"], "batch-0");
  EXPECT_EQ(listed("").size(), 3u);
  const HttpReply again = submit_job(port(), single, {{"Idempotency-Key", "z#0"}});  // still the single job
  EXPECT_EQ(again.json().value("id", ""), single_id) << again.body;
}

TEST_F(QueueE2E, ABatchThatDoesNotFitTheQueueIs429) {
  start({"--max-queue", "3"});
  hold_worker();
  const std::string queued = submit(image_job());
  const HttpReply r = batch({image_job(), image_job(), image_job()});  // fits once the queued job has run
  EXPECT_TRUE(is_problem(r, 429, "queue-full")) << r.body;
  EXPECT_THAT(r.json().value("detail", ""), HasSubstr("this batch adds 3"));
  EXPECT_EQ(listed("?state=queued"), std::vector<std::string>{queued});
  release();
}

TEST_F(QueueE2E, DeletingAFinishedJobPurgesItAndItsFiles) {
  start();
  const std::string id = submit(image_job());
  ASSERT_EQ(wait_for_job(port(), id)["state"], "succeeded");
  ASSERT_EQ(result_folders(server_->data_dir(), id), std::vector<std::string>{id + ".1"});
  const HttpReply purged = http_request(port(), "DELETE", "/v1/jobs/" + id);
  EXPECT_EQ(purged.status, 204);
  EXPECT_TRUE(purged.body.empty());
  EXPECT_TRUE(result_folders(server_->data_dir(), id).empty());
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/" + id), 404, "not-found"));
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/" + id + "/files/warped.png"), 404, "not-found"));
  EXPECT_TRUE(is_problem(http_request(port(), "DELETE", "/v1/jobs/" + id), 404, "not-found"));
  // Unfinished jobs are canceled as before: queued → 200 canceled (and a second DELETE purges it).
  hold_worker();
  const std::string queued = submit(image_job());
  const HttpReply canceled = http_request(port(), "DELETE", "/v1/jobs/" + queued);
  EXPECT_EQ(canceled.status, 200);
  EXPECT_EQ(canceled.json()["state"], "canceled");
  EXPECT_EQ(http_request(port(), "DELETE", "/v1/jobs/" + queued).status, 204);
  release();
}

TEST_F(QueueE2E, CancelNeverPurgesAFinishedJob) {
  start();
  // Finished: 409 job-finished naming its state; the job, its result and its files stay.
  const std::string done = submit(image_job());
  ASSERT_EQ(wait_for_job(port(), done)["state"], "succeeded");
  const HttpReply refused = http_request(port(), "POST", "/v1/jobs/" + done + ":cancel");
  EXPECT_TRUE(is_problem(refused, 409, "job-finished")) << refused.body;
  EXPECT_THAT(refused.json().value("detail", ""), HasSubstr("already finished (succeeded)"));
  EXPECT_EQ(job_status(port(), done)["state"], "succeeded");
  EXPECT_EQ(result_folders(server_->data_dir(), done), std::vector<std::string>{done + ".1"});
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs/" + done + "/files/warped.png").status, 200);
  // Queued: 200 canceled at once; a second cancel finds it finished (canceled) and changes nothing.
  hold_worker();
  const std::string queued = submit(image_job());
  const HttpReply canceled = http_request(port(), "POST", "/v1/jobs/" + queued + ":cancel");
  EXPECT_EQ(canceled.status, 200) << canceled.body;
  EXPECT_EQ(canceled.json()["state"], "canceled");
  const HttpReply again = http_request(port(), "POST", "/v1/jobs/" + queued + ":cancel");
  EXPECT_TRUE(is_problem(again, 409, "job-finished")) << again.body;
  EXPECT_THAT(again.json().value("detail", ""), HasSubstr("already finished (canceled)"));
  EXPECT_EQ(job_status(port(), queued)["state"], "canceled");
  // Running: 202 with cancel_requested; it ends canceled.
  const HttpReply requested = http_request(port(), "POST", "/v1/jobs/" + held_ + ":cancel");
  EXPECT_EQ(requested.status, 202) << requested.body;
  EXPECT_EQ(requested.json()["state"], "running");
  EXPECT_EQ(requested.json()["cancel_requested"], true);
  EXPECT_EQ(wait_for_job(port(), held_)["state"], "canceled");
  // An unknown job is 404; query parameters are refused; GET of this path asks for a job "<id>:cancel": 404.
  EXPECT_TRUE(is_problem(http_request(port(), "POST", "/v1/jobs/job_nosuchjob:cancel"), 404, "not-found"));
  EXPECT_TRUE(is_problem(http_request(port(), "POST", "/v1/jobs/" + done + ":cancel?x=1"), 400, "bad-query"));
  const HttpReply wrong = http_request(port(), "GET", "/v1/jobs/" + done + ":cancel");
  EXPECT_EQ(wrong.status, 404) << wrong.body;  // GET reads it as the id "<id>:cancel": no such job
}

TEST_F(QueueE2E, ALongPollAnswersAtTheChangeOrAtTheDeadline) {
  start();
  hold_worker();
  const std::string id = submit(image_job());
  // Nothing changes for 1 s: answered after about that long, still queued.
  auto t = Clock::now();
  HttpReply r = http_request(port(), "GET", "/v1/jobs/" + id + "?wait=1");
  EXPECT_GE(seconds_since(t), 0.9);
  EXPECT_LT(seconds_since(t), 10.0);
  EXPECT_EQ(r.json()["state"], "queued");
  // A change (released: it runs, then succeeds) ends the wait long before the 30 s.
  std::thread later([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    release();
  });
  t = Clock::now();
  r = http_request(port(), "GET", "/v1/jobs/" + id + "?wait=30");
  later.join();
  EXPECT_LT(seconds_since(t), 20.0);
  EXPECT_EQ(r.status, 200);
  EXPECT_NE(r.json()["state"], "queued") << r.body;
  ASSERT_EQ(wait_for_job(port(), id)["state"], "succeeded");
  // Finished at arrival: answered at once.
  t = Clock::now();
  r = http_request(port(), "GET", "/v1/jobs/" + id + "?wait=60");
  EXPECT_LT(seconds_since(t), 5.0);
  EXPECT_EQ(r.json()["state"], "succeeded");
  for (const char* bad : {"?wait=61", "?wait=-1", "?wait=x", "?wait=", "?wait=1.5", "?other=1"}) {
    EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/" + id + bad), 400, "bad-query")) << bad;
  }
  EXPECT_TRUE(
      is_problem(http_request(port(), "GET", "/v1/jobs/job_aaaaaaaaaaaaaaaaaaaaaaaaaa?wait=5"), 404, "not-found"));
}

TEST_F(QueueE2E, SixtyFourWaitingLongPollsStarveNothing) {
  start({"--io-threads", "1", "--max-connections-per-client", "128"});
  hold_worker();
  const std::string id = submit(image_job());
  std::vector<std::unique_ptr<RawConnection>> waiting;
  for (int i = 0; i < 64; ++i) {
    waiting.push_back(std::make_unique<RawConnection>(port()));
    waiting.back()->send("GET /v1/jobs/" + id + "?wait=30 HTTP/1.1\r\nHost: x\r\n\r\n");
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // all 64 are waiting now
  auto t = Clock::now();
  EXPECT_EQ(http_request(port(), "GET", "/livez").status, 200);
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs?limit=1").status, 200);
  EXPECT_EQ(job_status(port(), id)["state"], "queued");
  EXPECT_LT(seconds_since(t), 3.0);  // a thread per waiting request would have run out long ago (1 I/O thread)
  // Canceling the job is the change every one of them waits for: all answer, canceled.
  t = Clock::now();
  ASSERT_EQ(http_request(port(), "DELETE", "/v1/jobs/" + id).status, 200);
  for (auto& c : waiting) {
    const HttpReply r = c->read_reply(20);
    ASSERT_EQ(r.status, 200);
    EXPECT_EQ(r.json()["state"], "canceled");
  }
  EXPECT_LT(seconds_since(t), 15.0);
  release();
}

TEST_F(QueueE2E, NodesAndTheirMetrics) {
  start({"--node-id", "farm-a", "--heartbeat-s", "0.2", "--lease-s", "2", "--workers", "2"});
  const nlohmann::json nodes = http_request(port(), "GET", "/v1/nodes").json();
  ASSERT_EQ(nodes["nodes"].size(), 1u) << nodes.dump();
  const nlohmann::json& n = nodes["nodes"][0];
  EXPECT_EQ(n["id"], "farm-a");
  EXPECT_EQ(n["address"], "127.0.0.1:" + std::to_string(port()));
  EXPECT_EQ(n["workers"], 2);
  EXPECT_EQ(n["pid"], server_->pid());
  EXPECT_EQ(n["alive"], true);
  EXPECT_EQ(n["running"], 0);
  // The heartbeat moves last_seen_at on.
  const std::string seen = n["last_seen_at"];
  std::string later = seen;
  for (int i = 0; i < 100 && later == seen; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    later = http_request(port(), "GET", "/v1/nodes").json()["nodes"][0]["last_seen_at"];
  }
  EXPECT_GT(later, seen);
  const std::string id = submit(image_job());
  EXPECT_EQ(wait_for_job(port(), id)["node"], "farm-a");
  const std::string metrics = http_request(port(), "GET", "/metrics").body;
  EXPECT_THAT(metrics, HasSubstr("\ntexwarpd_nodes_alive 1\n"));
  EXPECT_THAT(metrics, HasSubstr("\ntexwarpd_node_info{node=\"farm-a\","));
  EXPECT_THAT(metrics, HasSubstr("\ntexwarpd_jobs_fenced_total 0\n"));
  // A clean shutdown leaves the registry.
  server_->signal(SIGTERM);
  EXPECT_EQ(server_->wait_exit(30), 0);
  ServerProcess again(dir_ / "data", {"--node-id", "farm-b"});
  const nlohmann::json after = http_request(again.port(), "GET", "/v1/nodes").json();
  ASSERT_EQ(after["nodes"].size(), 1u) << after.dump();
  EXPECT_EQ(after["nodes"][0]["id"], "farm-b");
}

TEST_F(QueueE2E, RetryAfterIsTheQueueOverItsRecentThroughput) {
  const auto before_start = Clock::now();
  start({"--max-queue", "1"});
  const auto started = Clock::now();
  for (int i = 0; i < 3; ++i) ASSERT_EQ(wait_for_job(port(), submit(image_job()))["state"], "succeeded");
  hold_worker();
  submit(image_job());  // the one queued job
  const double least = seconds_since(started);
  const HttpReply full = submit_job(port(), image_job());
  const double most = seconds_since(before_start);
  ASSERT_TRUE(is_problem(full, 429, "queue-full")) << full.body;
  // 3 jobs finished since the server started (less than 5 minutes ago): 1 queued over 3 per the seconds it has been
  // up (at least 5), not over the whole 5 minutes (which gave 100 s).
  const int retry_after = std::stoi(full.header("retry-after"));
  EXPECT_GE(retry_after, static_cast<int>(std::ceil(std::max(least, 5.0) / 3.0)) - 1) << least;
  EXPECT_LE(retry_after, static_cast<int>(std::ceil(std::max(most, 5.0) / 3.0)) + 1) << most;
  release();
}

TEST(QueueFlags, BadStoreAndLeaseSettingsAreRefusedClearly) {
  const fs::path dir = test_folder();
  const auto refusal = [&](const std::vector<std::string>& args) {
    const std::string log = (dir / "log").string();
    std::string cmd = std::string(TEXWARPD_BINARY) + " --data-dir " + (dir / "data").string();
    for (const auto& a : args) cmd += " '" + a + "'";
    const int status = std::system((cmd + " > " + log + " 2>&1").c_str());
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    return std::make_pair(WEXITSTATUS(status), text.str());
  };
  auto [code, out] = refusal({"--lease-s", "2", "--heartbeat-s", "1"});
  EXPECT_EQ(code, 2);
  EXPECT_THAT(out, HasSubstr("--heartbeat-s 1 must be less than half of --lease-s 2"));
  std::tie(code, out) = refusal({"--store", "mysql://farm:s3cret@db/texwarp"});
  EXPECT_EQ(code, 2);
  EXPECT_THAT(out, HasSubstr("--store: expected \"sqlite\" or a PostgreSQL URI"));
  EXPECT_THAT(out, HasSubstr("mysql://farm@db/texwarp"));
  EXPECT_THAT(out, Not(HasSubstr("s3cret")));
  // libpq decodes parameter names and takes the last of a repeated one: every spelling of a password is left out.
  std::tie(code, out) = refusal({"--store", "mysql://db/texwarp?password=s3cret1&pass%77ord=s3cret2&password=s3cret3"});
  EXPECT_EQ(code, 2);
  EXPECT_THAT(out, HasSubstr("mysql://db/texwarp"));
  EXPECT_THAT(out, Not(HasSubstr("s3cret")));
  std::tie(code, out) = refusal({"--lease-s", "0"});
  EXPECT_EQ(code, 2);
  std::tie(code, out) = refusal({"--poll-ms", "5"});
  EXPECT_EQ(code, 2);
  std::tie(code, out) = refusal({"--migrate"});
  EXPECT_EQ(code, 0) << out;
  EXPECT_THAT(out, HasSubstr("schema at version 2"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace texwarp::testing
