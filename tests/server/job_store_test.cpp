// The SQLite job store: insertion with idempotency keys, paging, the state machine (queued → running → final,
// cancel while queued or running) and recovery after a crash (re-queue, cancel, give up after max attempts).
#include <gtest/gtest.h>

#include "server_process.hpp"
#include "texwarp/server/job_store.hpp"

namespace texwarp::server {
namespace {

using proto::JobState;

NewJob job(const std::string& id, std::optional<std::string> key = std::nullopt, const std::string& sha = "s1") {
  NewJob j;
  j.id = id;
  j.name = "name-" + id;
  j.spec_json = R"({"spec": ")" + id + R"("})";
  j.body_sha256 = sha;
  j.idempotency_key = std::move(key);
  j.created_ms = 1000;
  return j;
}

TEST(JobStore, InsertsAndReadsBack) {
  const auto dir = testing::test_folder();
  JobStore store(dir / "jobs.sqlite3");
  EXPECT_FALSE(store.insert(job("a")).has_value());
  const auto row = store.get("a");
  ASSERT_TRUE(row);
  EXPECT_EQ(row->name, "name-a");
  EXPECT_EQ(row->state, JobState::kQueued);
  EXPECT_EQ(row->attempts, 0);
  EXPECT_EQ(row->created_ms, 1000);
  EXPECT_EQ(*store.spec_json("a"), R"({"spec": "a"})");
  EXPECT_FALSE(store.get("b"));
  EXPECT_TRUE(store.healthy());
}

TEST(JobStore, AnIdempotencyKeyInsertsOnceAndReturnsTheFirstJob) {
  const auto dir = testing::test_folder();
  JobStore store(dir / "jobs.sqlite3");
  EXPECT_FALSE(store.insert(job("a", "k1", "sha-a")));
  const auto again = store.insert(job("b", "k1", "sha-b"));
  ASSERT_TRUE(again);
  EXPECT_EQ(again->id, "a");
  EXPECT_EQ(again->body_sha256, "sha-a");
  EXPECT_FALSE(store.get("b"));
  EXPECT_EQ(store.find_by_idempotency_key("k1")->id, "a");
  EXPECT_FALSE(store.find_by_idempotency_key("k2"));
}

TEST(JobStore, PagesNewestFirstAndFiltersByState) {
  const auto dir = testing::test_folder();
  JobStore store(dir / "jobs.sqlite3");
  for (int i = 0; i < 7; ++i) store.insert(job("j" + std::to_string(i)));
  ASSERT_TRUE(store.mark_running("j2", 5));
  auto page = store.list(std::nullopt, 3, std::nullopt);
  ASSERT_EQ(page.size(), 3u);
  EXPECT_EQ(page[0].id, "j6");
  EXPECT_EQ(page[2].id, "j4");
  page = store.list(page.back().seq, 3, std::nullopt);
  EXPECT_EQ(page[0].id, "j3");
  page = store.list(page.back().seq, 3, std::nullopt);
  ASSERT_EQ(page.size(), 1u);
  EXPECT_EQ(page[0].id, "j0");
  const auto running = store.list(std::nullopt, 10, JobState::kRunning);
  ASSERT_EQ(running.size(), 1u);
  EXPECT_EQ(running[0].id, "j2");
  EXPECT_EQ(store.count(JobState::kQueued), 6);
}

TEST(JobStore, StateMachine) {
  const auto dir = testing::test_folder();
  JobStore store(dir / "jobs.sqlite3");
  store.insert(job("a"));
  store.insert(job("b"));
  store.insert(job("c"));
  EXPECT_EQ(store.request_cancel("a", 7), CancelOutcome::kCanceled);
  EXPECT_FALSE(store.mark_running("a", 8));  // canceled while queued: never runs
  EXPECT_EQ(store.get("a")->state, JobState::kCanceled);
  EXPECT_EQ(*store.get("a")->finished_ms, 7);

  ASSERT_TRUE(store.mark_running("b", 9));
  EXPECT_FALSE(store.mark_running("b", 9));  // only once
  EXPECT_EQ(store.get("b")->attempts, 1);
  EXPECT_EQ(store.request_cancel("b", 10), CancelOutcome::kRequested);
  EXPECT_TRUE(store.get("b")->cancel_requested);
  EXPECT_EQ(store.get("b")->state, JobState::kRunning);
  store.mark_finished("b", JobState::kCanceled, 11, 40, "", "");
  EXPECT_EQ(store.request_cancel("b", 12), CancelOutcome::kAlreadyFinal);
  EXPECT_EQ(store.request_cancel("zzz", 12), CancelOutcome::kNotFound);

  ASSERT_TRUE(store.mark_running("c", 13));
  store.requeue("c");  // graceful shutdown: the attempt is given back
  EXPECT_EQ(store.get("c")->state, JobState::kQueued);
  EXPECT_EQ(store.get("c")->attempts, 0);
  ASSERT_TRUE(store.mark_running("c", 14));
  store.mark_finished("c", JobState::kSucceeded, 15, 100, "", R"({"files": []})");
  EXPECT_EQ(store.get("c")->result_json, R"({"files": []})");
  EXPECT_EQ(store.get("c")->progress, 100);
}

TEST(JobStore, RecoveryRequeuesCancelsAndGivesUp) {
  const auto dir = testing::test_folder();
  {
    JobStore store(dir / "jobs.sqlite3");
    for (const char* id : {"queued", "running", "canceling", "crashy", "done"}) store.insert(job(id));
    store.mark_running("running", 1);
    store.mark_running("canceling", 1);
    store.request_cancel("canceling", 2);
    store.mark_running("crashy", 1);
    store.mark_running("done", 1);
    store.mark_finished("done", JobState::kSucceeded, 2, 100, "", "{}");
    // The crashy job has been found running at two restarts already.
    for (int i = 0; i < 2; ++i) {
      store.recover(99, 3);
      for (const auto& id : {"running", "canceling", "crashy"}) store.mark_running(id, 4);
    }
  }
  JobStore store(dir / "jobs.sqlite3");  // as after a crash: a new process opens the same file
  EXPECT_EQ(store.get("crashy")->attempts, 3);
  const Recovery r = store.recover(3, 5);
  EXPECT_EQ(r.failed, 2);  // "running" has 3 attempts as well
  EXPECT_EQ(r.canceled, 0);
  EXPECT_EQ(store.get("crashy")->state, JobState::kFailed);
  EXPECT_NE(store.get("crashy")->error_json.find("attempts-exhausted"), std::string::npos);
  EXPECT_EQ(store.get("canceling")->state, JobState::kCanceled);  // canceled at the first recovery
  EXPECT_EQ(store.get("done")->state, JobState::kSucceeded);
  ASSERT_EQ(r.queued.size(), 1u);
  EXPECT_EQ(r.queued[0], "queued");
}

TEST(JobStore, RecoveryKeepsInsertionOrder) {
  const auto dir = testing::test_folder();
  JobStore store(dir / "jobs.sqlite3");
  for (int i = 0; i < 5; ++i) store.insert(job("j" + std::to_string(i)));
  store.mark_running("j3", 1);
  const Recovery r = store.recover(3, 2);
  EXPECT_EQ(r.requeued, 1);
  EXPECT_EQ(r.queued, (std::vector<std::string>{"j0", "j1", "j2", "j3", "j4"}));
}

TEST(JobStore, RetentionDeletesOnlyOldFinishedJobs) {
  const auto dir = testing::test_folder();
  JobStore store(dir / "jobs.sqlite3");
  for (const char* id : {"old", "new", "queued"}) store.insert(job(id));
  store.mark_running("old", 1);
  store.mark_finished("old", JobState::kSucceeded, 100, 100, "", "{}");
  store.mark_running("new", 1);
  store.mark_finished("new", JobState::kFailed, 300, 3, "{}", "");
  EXPECT_EQ(store.delete_finished_before(200), std::vector<std::string>{"old"});
  EXPECT_FALSE(store.get("old"));
  EXPECT_TRUE(store.get("new"));
  EXPECT_TRUE(store.get("queued"));
}

}  // namespace
}  // namespace texwarp::server
