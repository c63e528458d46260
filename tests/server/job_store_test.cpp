// The job store suite, run against every JobStore implementation: insertion with idempotency keys (also two nodes
// at once; the lookup by key), batches, paging and filters, the claim order and its exclusivity across nodes, leases,
// fencing, cancel, reclaiming expired leases, purge, retention, the node registry and the maintenance lock.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <barrier>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "job_store_backends.hpp"
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

NewJob job_with(const std::string& id, int priority, Labels labels = {}) {
  NewJob j = job(id);
  j.priority = priority;
  j.labels = std::move(labels);
  return j;
}

std::vector<std::string> ids(const std::vector<JobRow>& rows) {
  std::vector<std::string> out;
  out.reserve(rows.size());
  for (const auto& row : rows) out.push_back(row.id);
  return out;
}

// A ListQuery, built up: Q().limit(3).state(JobState::kQueued).
struct Q : ListQuery {
  Q& before(std::int64_t seq) {
    before_seq = seq;
    return *this;
  }
  Q& limit(int n) {
    ListQuery::limit = n;
    return *this;
  }
  Q& state(JobState s) {
    ListQuery::state = s;
    return *this;
  }
  Q& labels(Labels l) {
    ListQuery::labels = std::move(l);
    return *this;
  }
};

constexpr std::int64_t kLease = 30'000;

class JobStoreSuite : public ::testing::TestWithParam<testing::StoreBackend> {
 protected:
  void SetUp() override {
    database_ = testing::make_store_database(GetParam());
    store_ = database_->open();
  }
  // Another store object on the same database: another node (or, for SQLite, another process after a crash).
  std::unique_ptr<JobStore> open_node() { return database_->open(); }
  JobStore& store() { return *store_; }
  // Claims the next job; fails the test when nothing is queued.
  Lease claim_next(const std::string& node = "n1", std::int64_t now = 1, JobStore* on = nullptr) {
    auto lease = (on ? on : store_.get())->claim(node, now, kLease);
    if (!lease) ADD_FAILURE() << "nothing to claim";
    return lease.value_or(Lease{});
  }

  std::unique_ptr<testing::StoreDatabase> database_;
  std::unique_ptr<JobStore> store_;
};

TEST_P(JobStoreSuite, InsertsAndReadsBack) {
  const Inserted inserted = store().insert(job_with("a", 7, {{"team", "fx"}, {"shot", "010"}}));
  EXPECT_FALSE(inserted.existed);
  EXPECT_EQ(inserted.row.id, "a");
  EXPECT_EQ(inserted.row.state, JobState::kQueued);
  const auto row = store().get("a");
  ASSERT_TRUE(row);
  EXPECT_EQ(row->seq, inserted.row.seq);
  EXPECT_EQ(row->name, "name-a");
  EXPECT_EQ(row->state, JobState::kQueued);
  EXPECT_EQ(row->priority, 7);
  EXPECT_EQ(row->labels, (Labels{{"shot", "010"}, {"team", "fx"}}));
  EXPECT_EQ(row->attempts, 0);
  EXPECT_EQ(row->created_ms, 1000);
  EXPECT_EQ(row->body_sha256, "s1");
  EXPECT_EQ(row->node_id, "");
  EXPECT_EQ(row->lease_epoch, 0);
  EXPECT_FALSE(row->lease_expires_ms);
  EXPECT_FALSE(row->started_ms);
  EXPECT_EQ(row->result_folder, "");
  EXPECT_EQ(*store().spec_json("a"), R"({"spec": "a"})");
  EXPECT_FALSE(store().get("b"));
  EXPECT_FALSE(store().spec_json("b"));
  EXPECT_TRUE(store().healthy());
  EXPECT_EQ(store().schema_version(), JobStore::kSchemaVersion);
}

TEST_P(JobStoreSuite, AnIdempotencyKeyInsertsOnceAndReturnsTheFirstJob) {
  EXPECT_FALSE(store().insert(job("a", "k1", "sha-a")).existed);
  const Inserted again = store().insert(job("b", "k1", "sha-b"));
  EXPECT_TRUE(again.existed);
  EXPECT_EQ(again.row.id, "a");
  EXPECT_EQ(again.row.body_sha256, "sha-a");
  EXPECT_FALSE(store().get("b"));
  const Inserted other = store().insert(job("c", "k2", "sha-c"));
  EXPECT_FALSE(other.existed);
  EXPECT_EQ(other.row.id, "c");
  EXPECT_EQ(store().count(JobState::kQueued), 2);
}

TEST_P(JobStoreSuite, FindsAJobByItsIdempotencyKey) {
  EXPECT_FALSE(store().find_by_idempotency_key("k1"));
  store().insert(job("plain"));
  store().insert(job("a", "k1", "sha-a"));
  store().insert_batch({job("b0", "kb#0", "sha-b0"), job("b1", "kb#1", "sha-b1")});
  const auto a = store().find_by_idempotency_key("k1");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->id, "a");
  EXPECT_EQ(a->body_sha256, "sha-a");
  EXPECT_EQ(a->state, JobState::kQueued);
  const auto b1 = store().find_by_idempotency_key("kb#1");
  ASSERT_TRUE(b1);
  EXPECT_EQ(b1->id, "b1");
  EXPECT_EQ(b1->body_sha256, "sha-b1");
  EXPECT_FALSE(store().find_by_idempotency_key("kb"));    // a batch's key stands for its jobs, not for a job
  EXPECT_FALSE(store().find_by_idempotency_key("kb#2"));  // past the batch's end
  EXPECT_FALSE(store().find_by_idempotency_key("K1"));    // keys are exact
  EXPECT_FALSE(store().find_by_idempotency_key(""));      // a job without a key is never found by one
  // The row as it is now, not as it was inserted.
  const Lease lease = claim_next();
  ASSERT_EQ(lease.job_id, "plain");
  ASSERT_EQ(claim_next().job_id, "a");
  const auto running = store().find_by_idempotency_key("k1");
  ASSERT_TRUE(running);
  EXPECT_EQ(running->state, JobState::kRunning);
  EXPECT_EQ(running->attempts, 1);
}

TEST_P(JobStoreSuite, TwoNodesInsertingTheSameKeyAtOnceMakeOneJob) {
  auto node2 = open_node();
  constexpr int kThreads = 2 * 4;  // 4 on each node (even t: the first)
  constexpr int kKeys = 10;
  for (int k = 0; k < kKeys; ++k) {
    const std::string key = "key-" + std::to_string(k);
    std::barrier start(kThreads);
    std::vector<Inserted> answers(kThreads);
    std::vector<std::string> errors(kThreads);
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
      JobStore& on = t % 2 == 0 ? store() : *node2;
      threads.emplace_back([&, t] {
        start.arrive_and_wait();
        try {
          answers[t] = on.insert(job(key + "-job-" + std::to_string(t), key, "sha-" + std::to_string(t)));
        } catch (const std::exception& e) {
          errors[t] = e.what();
        }
      });
    }
    for (auto& thread : threads) thread.join();
    int inserted = 0;
    for (int t = 0; t < kThreads; ++t) {
      ASSERT_EQ(errors[t], "") << "thread " << t;
      if (!answers[t].existed) ++inserted;
      EXPECT_EQ(answers[t].row.id, answers[0].row.id) << "thread " << t;
    }
    EXPECT_EQ(inserted, 1) << key;
  }
  EXPECT_EQ(store().count(JobState::kQueued), kKeys);
  EXPECT_EQ(node2->count(JobState::kQueued), kKeys);
}

TEST_P(JobStoreSuite, ABatchIsStoredInOrderAndAnswersEachJob) {
  store().insert(job("old", "k-old", "sha-old"));
  std::vector<NewJob> batch = {job_with("b0", 1), job("b1", "k-old", "sha-new"), job("b2", "k-new")};
  const auto answers = store().insert_batch(batch);
  ASSERT_EQ(answers.size(), 3u);
  EXPECT_FALSE(answers[0].existed);
  EXPECT_EQ(answers[0].row.id, "b0");
  EXPECT_EQ(answers[0].row.priority, 1);
  EXPECT_TRUE(answers[1].existed);
  EXPECT_EQ(answers[1].row.id, "old");
  EXPECT_FALSE(answers[2].existed);
  EXPECT_EQ(answers[2].row.id, "b2");
  EXPECT_LT(answers[0].row.seq, answers[2].row.seq);
  EXPECT_FALSE(store().get("b1"));
  EXPECT_EQ(store().count(JobState::kQueued), 3);
}

TEST_P(JobStoreSuite, ABatchWithADuplicateIdInTheMiddleStoresNothing) {
  store().insert(job("taken"));
  const std::vector<NewJob> batch = {job("n0", "k0"), job("n1"), job("taken"), job("n3"), job("n4", "k4")};
  EXPECT_ANY_THROW(store().insert_batch(batch));
  for (const char* id : {"n0", "n1", "n3", "n4"}) EXPECT_FALSE(store().get(id)) << id;
  EXPECT_EQ(store().count(JobState::kQueued), 1);
  // The keys of the failed batch were not taken either.
  EXPECT_FALSE(store().insert(job("again", "k0")).existed);
  EXPECT_TRUE(store().healthy());
}

TEST_P(JobStoreSuite, PagesNewestFirstAndFiltersByState) {
  for (int i = 0; i < 7; ++i) store().insert(job("j" + std::to_string(i)));
  EXPECT_EQ(claim_next().job_id, "j0");
  auto page = store().list(Q().limit(3));
  ASSERT_EQ(page.size(), 3u);
  EXPECT_EQ(page[0].id, "j6");
  EXPECT_EQ(page[2].id, "j4");
  page = store().list(Q().before(page.back().seq).limit(3));
  EXPECT_EQ(ids(page), (std::vector<std::string>{"j3", "j2", "j1"}));
  page = store().list(Q().before(page.back().seq).limit(3));
  ASSERT_EQ(page.size(), 1u);
  EXPECT_EQ(page[0].id, "j0");
  EXPECT_TRUE(store().list(Q().before(page.back().seq).limit(3)).empty());
  const auto running = store().list(Q().limit(10).state(JobState::kRunning));
  ASSERT_EQ(running.size(), 1u);
  EXPECT_EQ(running[0].id, "j0");
  EXPECT_EQ(store().count(JobState::kQueued), 6);
  EXPECT_EQ(store().count(JobState::kRunning), 1);
  EXPECT_EQ(store().count(JobState::kSucceeded), 0);
}

TEST_P(JobStoreSuite, FiltersByLabelsAllOfThem) {
  store().insert(job_with("a", 0, {{"team", "fx"}, {"shot", "010"}}));
  store().insert(job_with("b", 0, {{"team", "lighting"}}));
  store().insert(job_with("c", 0, {{"team", "fx"}}));
  store().insert(job_with("d", 0, {{"team", "fx"}, {"shot", "020"}}));
  store().insert(job_with("e", 0, {}));
  // Characters that quote or escape in SQL or JSON match only themselves.
  store().insert(job_with("q", 0, {{"it's", "a \"quoted\" \\ value ü"}}));
  EXPECT_EQ(ids(store().list(Q().labels({{"team", "fx"}}))), (std::vector<std::string>{"d", "c", "a"}));
  EXPECT_EQ(ids(store().list(Q().labels({{"team", "fx"}, {"shot", "010"}}))), std::vector<std::string>{"a"});
  EXPECT_TRUE(store().list(Q().labels({{"team", "fx"}, {"shot", "030"}})).empty());
  EXPECT_TRUE(store().list(Q().labels({{"shot", "fx"}})).empty());  // a value under another key does not count
  EXPECT_EQ(ids(store().list(Q().labels({{"it's", "a \"quoted\" \\ value ü"}}))), std::vector<std::string>{"q"});
  EXPECT_TRUE(store().list(Q().labels({{"it's", "a \"quoted\""}})).empty());
  // With the cursor and a state.
  const auto first = store().list(Q().limit(1).labels({{"team", "fx"}}));
  ASSERT_EQ(ids(first), std::vector<std::string>{"d"});
  EXPECT_EQ(ids(store().list(Q().before(first[0].seq).limit(1).labels({{"team", "fx"}}))),
            std::vector<std::string>{"c"});
  EXPECT_EQ(claim_next().job_id, "a");
  EXPECT_EQ(ids(store().list(Q().state(JobState::kQueued).labels({{"team", "fx"}}))),
            (std::vector<std::string>{"d", "c"}));
  EXPECT_EQ(ids(store().list(Q().state(JobState::kRunning).labels({{"team", "fx"}}))), std::vector<std::string>{"a"});
}

TEST_P(JobStoreSuite, ClaimsTheHighestPriorityFirstAndFifoWithin) {
  store().insert(job_with("low", -3));
  store().insert(job_with("mid1", 0));
  store().insert(job_with("high1", 5));
  store().insert(job_with("mid2", 0));
  store().insert(job_with("high2", 5));
  store().insert(job_with("top", 1000));
  std::vector<std::string> order;
  while (auto lease = store().claim("n1", 50, 100)) order.push_back(lease->job_id);
  EXPECT_EQ(order, (std::vector<std::string>{"top", "high1", "high2", "mid1", "mid2", "low"}));
  EXPECT_FALSE(store().claim("n1", 50, 100));
  EXPECT_EQ(store().count(JobState::kRunning), 6);
}

TEST_P(JobStoreSuite, AClaimLeasesTheJobToTheNode) {
  store().insert(job("a"));
  const auto lease = store().claim("node-7", 5000, 1234);
  ASSERT_TRUE(lease);
  EXPECT_EQ(lease->job_id, "a");
  EXPECT_EQ(lease->epoch, 1);
  EXPECT_EQ(lease->attempt, 1);
  EXPECT_EQ(lease->spec_json, R"({"spec": "a"})");
  const auto row = store().get("a");
  EXPECT_EQ(row->state, JobState::kRunning);
  EXPECT_EQ(row->node_id, "node-7");
  EXPECT_EQ(row->lease_epoch, 1);
  EXPECT_EQ(row->lease_expires_ms, 6234);
  EXPECT_EQ(row->started_ms, 5000);
  EXPECT_EQ(row->attempts, 1);
  EXPECT_FALSE(store().claim("node-7", 5000, 1234));  // only once
}

TEST_P(JobStoreSuite, TwoNodesWithFourThreadsEachClaimEveryJobExactlyOnce) {
  constexpr int kJobs = 200;
  std::vector<NewJob> jobs;
  jobs.reserve(kJobs);
  for (int i = 0; i < kJobs; ++i) jobs.push_back(job_with("j" + std::to_string(i), i % 3));
  store().insert_batch(jobs);
  auto node2 = open_node();
  constexpr int kThreads = 2 * 4;  // 4 on each node (even t: the first)
  std::barrier start(kThreads);
  std::vector<std::vector<std::string>> claimed(kThreads);
  std::vector<std::string> errors(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    JobStore& on = t % 2 == 0 ? store() : *node2;
    const std::string node = t % 2 == 0 ? "n1" : "n2";
    threads.emplace_back([&, t, node] {
      start.arrive_and_wait();
      try {
        while (auto lease = on.claim(node, 10, kLease)) claimed[t].push_back(lease->job_id);
      } catch (const std::exception& e) {
        errors[t] = e.what();
      }
    });
  }
  for (auto& thread : threads) thread.join();
  std::multiset<std::string> all;
  for (int t = 0; t < kThreads; ++t) {
    EXPECT_EQ(errors[t], "") << "thread " << t;
    all.insert(claimed[t].begin(), claimed[t].end());
  }
  EXPECT_EQ(all.size(), static_cast<std::size_t>(kJobs));
  EXPECT_EQ(std::set<std::string>(all.begin(), all.end()).size(), static_cast<std::size_t>(kJobs));
  EXPECT_EQ(store().count(JobState::kRunning), kJobs);
  EXPECT_EQ(store().count(JobState::kQueued), 0);
  for (const auto& row : store().list(Q().limit(kJobs))) {
    EXPECT_EQ(row.attempts, 1) << row.id;
    EXPECT_EQ(row.lease_epoch, 1) << row.id;
  }
}

TEST_P(JobStoreSuite, RenewExtendsTheLeaseStoresProgressAndReportsCancel) {
  store().insert(job("a"));
  const auto lease = store().claim("n1", 1000, 500);
  ASSERT_TRUE(lease);
  EXPECT_EQ(store().get("a")->lease_expires_ms, 1500);
  Renewal r = store().renew("a", lease->epoch, 30, 1400, 500);
  EXPECT_TRUE(r.held);
  EXPECT_FALSE(r.cancel_requested);
  EXPECT_EQ(store().get("a")->lease_expires_ms, 1900);
  EXPECT_EQ(store().get("a")->progress, 30);
  EXPECT_EQ(store().request_cancel("a", 1500), CancelOutcome::kRequested);
  r = store().renew("a", lease->epoch, 40, 1600, 500);
  EXPECT_TRUE(r.held);
  EXPECT_TRUE(r.cancel_requested);
  EXPECT_FALSE(store().renew("a", lease->epoch + 1, 50, 1600, 500).held);
  EXPECT_FALSE(store().renew("nope", 1, 50, 1600, 500).held);
  EXPECT_EQ(store().get("a")->progress, 40);
  // Another node sees the request too.
  EXPECT_TRUE(open_node()->renew("a", lease->epoch, 45, 1700, 500).cancel_requested);
}

TEST_P(JobStoreSuite, AnExpiredLeaseTakenOverFencesTheOldHolder) {
  store().insert(job("a"));
  const auto first = store().claim("n1", 0, 100);
  ASSERT_TRUE(first);
  EXPECT_TRUE(store().reclaim_expired(100, 3).requeued.empty());  // expires at 100: not yet
  const Reclaimed r = store().reclaim_expired(101, 3);
  EXPECT_EQ(r.requeued, std::vector<std::string>{"a"});
  EXPECT_EQ(r.failed, 0);
  EXPECT_EQ(r.canceled, 0);
  auto node2 = open_node();
  const auto second = node2->claim("n2", 200, 100);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->job_id, "a");
  EXPECT_EQ(second->epoch, first->epoch + 1);
  EXPECT_EQ(second->attempt, 2);
  // The old holder wakes up: everything it says is refused.
  EXPECT_FALSE(store().renew("a", first->epoch, 99, 210, 100).held);
  EXPECT_FALSE(store().finish("a", first->epoch, JobState::kSucceeded, 220, 100, "", R"({"old": 1})", "a.1"));
  EXPECT_FALSE(store().release("a", first->epoch));
  auto row = store().get("a");
  EXPECT_EQ(row->state, JobState::kRunning);
  EXPECT_EQ(row->node_id, "n2");
  EXPECT_EQ(row->result_folder, "");
  // The new holder is heard.
  EXPECT_TRUE(node2->renew("a", second->epoch, 60, 230, 100).held);
  EXPECT_TRUE(node2->finish("a", second->epoch, JobState::kSucceeded, 240, 100, "", R"({"new": 2})", "a.2"));
  row = store().get("a");
  EXPECT_EQ(row->state, JobState::kSucceeded);
  EXPECT_EQ(row->result_json, R"({"new": 2})");
  EXPECT_EQ(row->result_folder, "a.2");
  EXPECT_EQ(row->finished_ms, 240);
  EXPECT_EQ(row->progress, 100);
  EXPECT_FALSE(row->lease_expires_ms);
  EXPECT_EQ(row->node_id, "n2");
  // Finished: no epoch is heard any more.
  EXPECT_FALSE(node2->finish("a", second->epoch, JobState::kFailed, 250, 0, "{}", "", ""));
  EXPECT_FALSE(node2->renew("a", second->epoch, 0, 250, 100).held);
  EXPECT_EQ(store().get("a")->state, JobState::kSucceeded);
}

TEST_P(JobStoreSuite, ReleaseGivesTheAttemptBack) {
  store().insert(job("c"));
  const Lease first = claim_next("n1", 13);
  EXPECT_TRUE(store().release("c", first.epoch));  // graceful shutdown: the attempt is given back
  auto row = store().get("c");
  EXPECT_EQ(row->state, JobState::kQueued);
  EXPECT_EQ(row->attempts, 0);
  EXPECT_FALSE(row->lease_expires_ms);
  EXPECT_FALSE(row->started_ms);
  EXPECT_FALSE(store().release("c", first.epoch));  // not running any more
  const Lease second = claim_next("n2", 14);
  EXPECT_EQ(second.job_id, "c");
  EXPECT_EQ(second.attempt, 1);
  EXPECT_EQ(second.epoch, first.epoch + 1);
  EXPECT_TRUE(store().finish("c", second.epoch, JobState::kSucceeded, 15, 100, "", R"({"files": []})", "c.2"));
  EXPECT_EQ(store().get("c")->result_json, R"({"files": []})");
  EXPECT_EQ(store().get("c")->progress, 100);
}

TEST_P(JobStoreSuite, StateMachine) {
  store().insert(job("a"));
  store().insert(job("b"));
  EXPECT_EQ(store().request_cancel("a", 7), CancelOutcome::kCanceled);
  EXPECT_EQ(store().get("a")->state, JobState::kCanceled);
  EXPECT_EQ(*store().get("a")->finished_ms, 7);
  EXPECT_TRUE(store().get("a")->cancel_requested);

  const Lease b = claim_next("n1", 9);  // canceled while queued: never runs
  EXPECT_EQ(b.job_id, "b");
  EXPECT_FALSE(store().claim("n1", 9, kLease));
  EXPECT_EQ(store().get("b")->attempts, 1);
  EXPECT_EQ(store().request_cancel("b", 10), CancelOutcome::kRequested);
  EXPECT_TRUE(store().get("b")->cancel_requested);
  EXPECT_EQ(store().get("b")->state, JobState::kRunning);
  EXPECT_FALSE(store().get("b")->finished_ms);
  EXPECT_TRUE(store().finish("b", b.epoch, JobState::kCanceled, 11, 40, "", "", ""));
  EXPECT_EQ(store().get("b")->state, JobState::kCanceled);
  EXPECT_EQ(store().get("b")->progress, 40);
  EXPECT_EQ(store().request_cancel("b", 12), CancelOutcome::kAlreadyFinal);
  EXPECT_EQ(store().request_cancel("a", 12), CancelOutcome::kAlreadyFinal);
  EXPECT_EQ(store().request_cancel("zzz", 12), CancelOutcome::kNotFound);
  EXPECT_THROW(store().finish("b", b.epoch, JobState::kQueued, 13, 0, "", "", ""), std::invalid_argument);
}

TEST_P(JobStoreSuite, ReclaimRequeuesCancelsAndGivesUpAfterMaxAttempts) {
  for (const char* id : {"running", "canceling", "crashy", "done", "queued"}) store().insert(job(id));
  std::map<std::string, Lease> leases;
  for (int i = 0; i < 4; ++i) {
    const Lease lease = claim_next("n1", 1);
    leases[lease.job_id] = lease;
  }
  EXPECT_EQ(store().request_cancel("canceling", 2), CancelOutcome::kRequested);
  EXPECT_TRUE(store().finish("done", leases["done"].epoch, JobState::kSucceeded, 2, 100, "", "{}", "done.1"));
  // The leases expire twice more: each time the jobs are claimed again.
  for (int round = 0; round < 2; ++round) {
    const std::int64_t now = std::int64_t{1'000'000} * (round + 1);
    const Reclaimed r = store().reclaim_expired(now, 99);
    EXPECT_EQ(r.canceled, round == 0 ? 1 : 0);
    EXPECT_EQ(r.failed, 0);
    EXPECT_EQ(r.requeued, (std::vector<std::string>{"running", "crashy"}));
    EXPECT_EQ(claim_next("n1", now).job_id, "running");
    EXPECT_EQ(claim_next("n1", now).job_id, "crashy");
  }
  EXPECT_EQ(store().get("canceling")->state, JobState::kCanceled);  // canceled at the first reclaim
  EXPECT_EQ(store().get("canceling")->finished_ms, 1'000'000);
  auto restarted = open_node();  // as after a crash: a new process opens the same database
  EXPECT_EQ(restarted->get("crashy")->attempts, 3);
  const Reclaimed r = restarted->reclaim_expired(5'000'000, 3);
  EXPECT_EQ(r.failed, 2);  // "running" has 3 attempts as well
  EXPECT_EQ(r.canceled, 0);
  EXPECT_TRUE(r.requeued.empty());
  const auto crashy = restarted->get("crashy");
  EXPECT_EQ(crashy->state, JobState::kFailed);
  EXPECT_EQ(crashy->finished_ms, 5'000'000);
  EXPECT_FALSE(crashy->lease_expires_ms);
  EXPECT_NE(crashy->error_json.find("attempts-exhausted"), std::string::npos) << crashy->error_json;
  EXPECT_NE(crashy->error_json.find("3 times"), std::string::npos) << crashy->error_json;
  EXPECT_EQ(restarted->get("done")->state, JobState::kSucceeded);
  EXPECT_EQ(restarted->get("queued")->state, JobState::kQueued);
  EXPECT_EQ(restarted->get("queued")->attempts, 0);
}

TEST_P(JobStoreSuite, ReclaimKeepsInsertionOrder) {
  for (int i = 0; i < 5; ++i) store().insert(job("j" + std::to_string(i)));
  for (int i = 0; i < 3; ++i) claim_next("n1", 1);
  const Reclaimed r = store().reclaim_expired(1 + kLease + 1, 3);
  EXPECT_EQ(r.requeued, (std::vector<std::string>{"j0", "j1", "j2"}));
  std::vector<std::string> order;
  while (auto lease = store().claim("n1", 2 * kLease, kLease)) order.push_back(lease->job_id);
  EXPECT_EQ(order, (std::vector<std::string>{"j0", "j1", "j2", "j3", "j4"}));
}

TEST_P(JobStoreSuite, ReclaimByNodeTakesEveryLeaseOfThatNodeOnly) {
  for (const char* id : {"a", "b", "c"}) store().insert(job(id));
  claim_next("n1", 1);
  claim_next("n2", 1);
  claim_next("n1", 1);
  const Reclaimed r = store().reclaim_expired(2, 3, std::string("n1"));  // leases far from expiry
  EXPECT_EQ(r.requeued, (std::vector<std::string>{"a", "c"}));
  EXPECT_EQ(store().get("b")->state, JobState::kRunning);
  EXPECT_EQ(store().get("a")->state, JobState::kQueued);
  EXPECT_TRUE(store().reclaim_expired(2, 3).requeued.empty());
}

TEST_P(JobStoreSuite, PurgeDeletesOnlyFinishedJobs) {
  for (const char* id : {"queued", "running", "done"}) store().insert(job(id));
  EXPECT_EQ(claim_next().job_id, "queued");
  store().request_cancel("queued", 3);  // canceled while running: still running
  const Lease running = claim_next();
  const Lease done = claim_next();
  EXPECT_TRUE(store().finish("done", done.epoch, JobState::kFailed, 5, 10, R"({"x": 1})", "", ""));
  EXPECT_EQ(store().purge("nope"), PurgeOutcome::kNotFound);
  EXPECT_EQ(store().purge("running"), PurgeOutcome::kNotFinished);
  EXPECT_EQ(store().purge("queued"), PurgeOutcome::kNotFinished);
  EXPECT_EQ(store().purge("done"), PurgeOutcome::kPurged);
  EXPECT_FALSE(store().get("done"));
  EXPECT_EQ(store().purge("done"), PurgeOutcome::kNotFound);
  EXPECT_FALSE(store().renew("done", done.epoch, 0, 6, kLease).held);
  EXPECT_TRUE(store().get("running"));
  store().insert(job("queued2"));
  EXPECT_EQ(store().purge("queued2"), PurgeOutcome::kNotFinished);
  EXPECT_TRUE(store().renew("running", running.epoch, 1, 6, kLease).held);
}

TEST_P(JobStoreSuite, RetentionDeletesOnlyOldFinishedJobs) {
  for (const char* id : {"old", "new", "queued"}) store().insert(job(id));
  const Lease old_lease = claim_next();
  EXPECT_TRUE(store().finish("old", old_lease.epoch, JobState::kSucceeded, 100, 100, "", "{}", "old.1"));
  const Lease new_lease = claim_next();
  EXPECT_TRUE(store().finish("new", new_lease.epoch, JobState::kFailed, 300, 3, "{}", "", ""));
  EXPECT_EQ(store().delete_finished_before(200), std::vector<std::string>{"old"});
  EXPECT_FALSE(store().get("old"));
  EXPECT_TRUE(store().get("new"));
  EXPECT_TRUE(store().get("queued"));
  EXPECT_TRUE(store().delete_finished_before(200).empty());
}

TEST_P(JobStoreSuite, FinishedSinceCountsEveryFinalStateFromThen) {
  for (int i = 0; i < 5; ++i) store().insert(job("j" + std::to_string(i)));
  const Lease a = claim_next();
  const Lease b = claim_next();
  const Lease c = claim_next();
  claim_next();  // j3 stays running
  EXPECT_TRUE(store().finish(a.job_id, a.epoch, JobState::kSucceeded, 100, 100, "", "{}", "j0.1"));
  EXPECT_TRUE(store().finish(b.job_id, b.epoch, JobState::kFailed, 200, 5, "{}", "", ""));
  EXPECT_TRUE(store().finish(c.job_id, c.epoch, JobState::kCanceled, 300, 5, "", "", ""));
  EXPECT_EQ(store().request_cancel("j4", 400), CancelOutcome::kCanceled);
  EXPECT_EQ(store().finished_since(0).count, 4);
  EXPECT_EQ(store().finished_since(0).oldest_ms, 100);
  EXPECT_EQ(store().finished_since(200).count, 3);
  EXPECT_EQ(store().finished_since(200).oldest_ms, 200);
  EXPECT_EQ(store().finished_since(201).count, 2);
  EXPECT_EQ(store().finished_since(201).oldest_ms, 300);
  EXPECT_EQ(store().finished_since(401).count, 0);
  EXPECT_FALSE(store().finished_since(401).oldest_ms);
}

TEST_P(JobStoreSuite, NodesRegisterHeartbeatAndLeave) {
  EXPECT_TRUE(store().nodes().empty());
  store().register_node({"b:8080", "10.0.0.2:8080", "0.1.0", 4, 222, 1000, 1000, 0});
  store().register_node({"a:8080", "10.0.0.1:8080", "0.1.0", 2, 111, 900, 950, 0});
  auto nodes = open_node()->nodes();
  ASSERT_EQ(nodes.size(), 2u);
  EXPECT_EQ(nodes[0].id, "a:8080");
  EXPECT_EQ(nodes[0].address, "10.0.0.1:8080");
  EXPECT_EQ(nodes[0].version, "0.1.0");
  EXPECT_EQ(nodes[0].workers, 2);
  EXPECT_EQ(nodes[0].pid, 111);
  EXPECT_EQ(nodes[0].started_ms, 900);
  EXPECT_EQ(nodes[0].last_seen_ms, 950);
  EXPECT_EQ(nodes[1].id, "b:8080");
  store().heartbeat_node("b:8080", 2000, 3);
  nodes = store().nodes();
  EXPECT_EQ(nodes[1].last_seen_ms, 2000);
  EXPECT_EQ(nodes[1].running, 3);
  EXPECT_EQ(nodes[0].last_seen_ms, 950);
  // A restarted node registers again under its id: one row, the new process.
  store().register_node({"b:8080", "10.0.0.2:8080", "0.2.0", 8, 333, 3000, 3000, 0});
  nodes = store().nodes();
  ASSERT_EQ(nodes.size(), 2u);
  EXPECT_EQ(nodes[1].pid, 333);
  EXPECT_EQ(nodes[1].workers, 8);
  EXPECT_EQ(nodes[1].version, "0.2.0");
  EXPECT_EQ(nodes[1].running, 0);
  store().remove_node("a:8080");
  nodes = store().nodes();
  ASSERT_EQ(nodes.size(), 1u);
  EXPECT_EQ(nodes[0].id, "b:8080");
  store().remove_node("a:8080");  // gone already: nothing happens
  store().heartbeat_node("ghost", 1, 1);
  EXPECT_EQ(store().nodes().size(), 1u);
}

TEST_P(JobStoreSuite, TheMaintenanceLockIsHeldByOneNodeAtATime) {
  auto node2 = open_node();
  auto lock = store().try_maintenance_lock();
  ASSERT_TRUE(lock);
  if (store().backend() == "sqlite") {
    // The single node (its data folder is locked to one process) always holds it.
    EXPECT_TRUE(node2->try_maintenance_lock());
    return;
  }
  EXPECT_FALSE(node2->try_maintenance_lock());
  EXPECT_FALSE(node2->try_maintenance_lock());
  lock.reset();
  auto lock2 = node2->try_maintenance_lock();
  EXPECT_TRUE(lock2);
  EXPECT_FALSE(store().try_maintenance_lock());
  node2.reset();  // the lock holds its own connection: it outlives the store object that made it
  EXPECT_FALSE(store().try_maintenance_lock());
  lock2.reset();
  EXPECT_TRUE(store().try_maintenance_lock());
}

INSTANTIATE_TEST_SUITE_P(Sqlite, JobStoreSuite, ::testing::Values(testing::StoreBackend::kSqlite),
                         [](const auto&) { return std::string("sqlite"); });
// Needs the test cluster (CTest's `postgres` fixture): the test names start with "Postgres".
INSTANTIATE_TEST_SUITE_P(Postgres, JobStoreSuite, ::testing::Values(testing::StoreBackend::kPostgres),
                         [](const auto&) { return std::string("postgresql"); });

}  // namespace
}  // namespace texwarp::server
