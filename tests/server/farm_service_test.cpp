// Nodes of a farm at the service level: two JobService instances (two nodes, each with its own store connection)
// on one job store, configured as farm nodes (leases reclaimed by any node, each node's own at its start). A run
// whose lease was taken over cannot publish (fenced: the served files are the winner's), a cancel sent to one node
// stops the job running on the other, the same Idempotency-Key sent to both at once makes one job, and a clean
// shutdown releases its leases and leaves the node registry. Runs on every store backend the suite has. And the real
// texwarpd on a PostgreSQL that restarts under load: 503 store-unavailable meanwhile, nothing lost after.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <barrier>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <memory>
#include <thread>

#include "api_helpers.hpp"
#include "job_store_backends.hpp"
#include "pg_test_cluster.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "test_time.hpp"
#include "texwarp/server/job_service.hpp"
#include "texwarp/server/timestamps.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using server::JobService;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// One node: its store connection, configuration, blobs, metrics and service.
struct Node {
  Node(std::unique_ptr<server::JobStore> s, const fs::path& data, const std::string& id, double lease_s,
       double heartbeat_s)
      : store(std::move(s)), blobs(data, server::BlobStore::Sharing::kShared) {
    config.data_dir = data;
    config.store = "postgresql://farm-node";  // a farm node's behaviour, whichever store is underneath
    config.node_id = id;
    config.workers = 1;
    config.threads_per_job = 1;
    config.device = proto::DeviceSpec::cpu();
    config.limits.max_job_memory_bytes = runner::default_job_memory_bytes(1);
    config.lease_s = lease_s;
    config.heartbeat_s = heartbeat_s;
    config.poll_ms = 50;
    service = std::make_unique<JobService>(config, *store, blobs, metrics);
    service->start(0);
  }

  std::string submit(const nlohmann::json& job, const std::optional<std::string>& key = std::nullopt) const {
    return service->submit(job.dump(), key).status.id;
  }
  proto::JobStatus status(const std::string& id) const { return service->status(id); }
  // Polls until `done` holds for the job's status (the test fails after `timeout_s`).
  proto::JobStatus wait(const std::string& id, const std::function<bool(const proto::JobStatus&)>& done,
                        double timeout_s = 60.0) const {
    const auto start = Clock::now();
    proto::JobStatus s = status(id);
    while (!done(s) && seconds_since(start) < wait_seconds(timeout_s)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      s = status(id);
    }
    EXPECT_TRUE(done(s)) << "job " << id << " still " << proto::to_string(s.state);
    return s;
  }
  proto::JobStatus wait_state(const std::string& id, proto::JobState state, double timeout_s = 60.0) const {
    return wait(
        id, [state](const proto::JobStatus& s) { return s.state == state; }, timeout_s);
  }

  std::unique_ptr<server::JobStore> store;
  server::ServerConfig config;
  server::BlobStore blobs;
  server::Metrics metrics;
  std::unique_ptr<JobService> service;
};

// A job store whose first `finish` is committed and then answered as a lost connection (StoreUnavailable): the
// reply to a write that the store took, lost on the way back, as when PostgreSQL's connection breaks after a
// commit. Every other call goes to the real store underneath.
class LostFirstFinishReply : public server::JobStore {
 public:
  explicit LostFirstFinishReply(std::unique_ptr<server::JobStore> inner) : inner_(std::move(inner)) {}
  std::string backend() const override { return inner_->backend(); }
  int schema_version() override { return inner_->schema_version(); }
  server::Inserted insert(const server::NewJob& job) override { return inner_->insert(job); }
  std::vector<server::Inserted> insert_batch(const std::vector<server::NewJob>& jobs) override {
    return inner_->insert_batch(jobs);
  }
  std::optional<server::JobRow> get(const std::string& id) override { return inner_->get(id); }
  std::optional<server::JobRow> find_by_idempotency_key(const std::string& key) override {
    return inner_->find_by_idempotency_key(key);
  }
  std::optional<std::string> spec_json(const std::string& id) override { return inner_->spec_json(id); }
  std::vector<server::JobRow> list(const server::ListQuery& query) override { return inner_->list(query); }
  std::optional<server::Lease> claim(const std::string& node_id, std::int64_t now_ms, std::int64_t lease_ms) override {
    return inner_->claim(node_id, now_ms, lease_ms);
  }
  server::Renewal renew(const std::string& id, std::int64_t epoch, int progress, std::int64_t now_ms,
                        std::int64_t lease_ms) override {
    return inner_->renew(id, epoch, progress, now_ms, lease_ms);
  }
  bool finish(const std::string& id, std::int64_t epoch, proto::JobState state, std::int64_t now_ms, int progress,
              const std::string& error_json, const std::string& result_json,
              const std::string& result_folder) override {
    const bool written = inner_->finish(id, epoch, state, now_ms, progress, error_json, result_json, result_folder);
    if (lost_.exchange(false)) throw server::StoreUnavailable("job store: the connection was lost (test)");
    return written;
  }
  bool release(const std::string& id, std::int64_t epoch) override { return inner_->release(id, epoch); }
  server::CancelOutcome request_cancel(const std::string& id, std::int64_t now_ms) override {
    return inner_->request_cancel(id, now_ms);
  }
  server::Reclaimed reclaim_expired(std::int64_t now_ms, int max_attempts,
                                    const std::optional<std::string>& node_id) override {
    return inner_->reclaim_expired(now_ms, max_attempts, node_id);
  }
  server::PurgeOutcome purge(const std::string& id) override { return inner_->purge(id); }
  std::vector<std::string> delete_finished_before(std::int64_t cutoff_ms) override {
    return inner_->delete_finished_before(cutoff_ms);
  }
  std::int64_t count(proto::JobState state) override { return inner_->count(state); }
  server::FinishedSince finished_since(std::int64_t since_ms) override { return inner_->finished_since(since_ms); }
  void register_node(const server::NodeInfo& node) override { inner_->register_node(node); }
  void heartbeat_node(const std::string& node_id, std::int64_t now_ms, int running) override {
    inner_->heartbeat_node(node_id, now_ms, running);
  }
  void remove_node(const std::string& node_id) override { inner_->remove_node(node_id); }
  std::vector<server::NodeInfo> nodes() override { return inner_->nodes(); }
  std::unique_ptr<server::MaintenanceLock> try_maintenance_lock() override { return inner_->try_maintenance_lock(); }
  std::string health() override { return inner_->health(); }

 private:
  std::unique_ptr<server::JobStore> inner_;
  std::atomic<bool> lost_{true};
};

class FarmService : public ::testing::TestWithParam<StoreBackend> {
 protected:
  void SetUp() override {
    db_ = make_store_database(GetParam());
    dir_ = test_folder();
    store_ = db_->open();
  }
  void TearDown() override {
    nodes_.clear();
    store_.reset();
    db_.reset();
    fs::remove_all(dir_);
  }
  Node& node(const std::string& id, double lease_s = 10.0, double heartbeat_s = 0.2) {
    nodes_.push_back(std::make_unique<Node>(db_->open(), dir_ / "data", id, lease_s, heartbeat_s));
    return *nodes_.back();
  }

  std::unique_ptr<StoreDatabase> db_;
  std::unique_ptr<server::JobStore> store_;  // the test's own view of the database
  fs::path dir_;
  std::vector<std::unique_ptr<Node>> nodes_;
};

TEST_P(FarmService, ARunWhoseLeaseWasTakenOverCannotPublish) {
  // Node A never renews within the test (its heartbeat is minutes away): it runs on after its lease is gone.
  Node& a = node("node-a", 600.0, 200.0);
  const std::string id = a.submit(slow_image_job(400));
  a.wait_state(id, proto::JobState::kRunning);
  // The lease expires (as after a long pause of A): reclaimed, queued again; node B takes it over under epoch 2.
  const server::Reclaimed r = store_->reclaim_expired(server::now_ms() + 3'600'000, 5);
  ASSERT_EQ(r.requeued, std::vector<std::string>{id});
  Node& b = node("node-b");
  const proto::JobStatus done = b.wait_state(id, proto::JobState::kSucceeded);
  EXPECT_EQ(done.node, "node-b");
  EXPECT_EQ(done.attempts, 2);
  // A's run ends too, and its outcome is refused: fenced, its own folder removed.
  const auto start = Clock::now();
  while (a.metrics.render({}).find("texwarpd_jobs_fenced_total 1\n") == std::string::npos &&
         seconds_since(start) < 60) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_THAT(a.metrics.render({}), ::testing::HasSubstr("texwarpd_jobs_fenced_total 1\n"));
  EXPECT_THAT(b.metrics.render({}), ::testing::HasSubstr("texwarpd_jobs_fenced_total 0\n"));
  const auto row = store_->get(id);
  ASSERT_TRUE(row);
  EXPECT_EQ(row->state, proto::JobState::kSucceeded);
  EXPECT_EQ(row->result_folder, id + ".2");
  EXPECT_EQ(row->lease_epoch, 2);
  EXPECT_EQ(result_folders(dir_ / "data", id), std::vector<std::string>{id + ".2"});
  // Both nodes serve the winner's files.
  for (Node* n : {&a, &b}) {
    std::string media_type;
    std::string sha256;
    const fs::path file = n->service->result_file(id, "warped.png", &media_type, &sha256);
    EXPECT_EQ(file.parent_path().filename(), id + ".2");
    EXPECT_TRUE(fs::exists(file));
  }
  EXPECT_EQ(a.service->result(id).files.size(), b.service->result(id).files.size());
}

TEST_P(FarmService, AHeartbeatThatFindsItsLeaseLostStopsTheRunAndRecordsNothing) {
  Node& a = node("node-a", 10.0, 0.1);
  const std::string id = a.submit(slow_image_job(800));
  a.wait_state(id, proto::JobState::kRunning);
  const auto start = Clock::now();
  ASSERT_EQ(store_->reclaim_expired(server::now_ms() + 3'600'000, 5).requeued, std::vector<std::string>{id});
  while (a.metrics.render({}).find("texwarpd_leases_lost_total 1\n") == std::string::npos &&
         seconds_since(start) < 30) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_THAT(a.metrics.render({}), ::testing::HasSubstr("texwarpd_leases_lost_total 1\n"));
  EXPECT_LT(seconds_since(start), 5.0);  // the next heartbeat (0.1 s) finds it; the run stops at its next tile
  // The job runs again under epoch 2 (here, the worker being free again) and only that run's folder exists.
  const proto::JobStatus done = a.wait_state(id, proto::JobState::kSucceeded);
  EXPECT_EQ(done.attempts, 2);
  EXPECT_EQ(result_folders(dir_ / "data", id), std::vector<std::string>{id + ".2"});
  EXPECT_THAT(a.metrics.render({}), ::testing::HasSubstr("texwarpd_jobs_fenced_total 0\n"));
}

TEST_P(FarmService, ACancelSentToOneNodeStopsTheJobRunningOnAnother) {
  Node& b = node("node-b");
  const std::string id = b.submit(slow_image_job(800));
  b.wait_state(id, proto::JobState::kRunning);
  Node& a = node("node-a");
  const auto start = Clock::now();
  const server::DeleteResult asked = a.service->remove(id);
  EXPECT_EQ(asked.action, server::DeleteResult::Action::kCancelRequested);
  EXPECT_TRUE(asked.status.cancel_requested);
  const proto::JobStatus done = a.wait_state(id, proto::JobState::kCanceled, 30.0);
  EXPECT_LT(seconds_since(start), 5.0);  // B's next heartbeat (0.2 s) sees it, the run stops at its next tile
  EXPECT_EQ(done.node, "node-b");
  EXPECT_LT(done.progress, 100);
  EXPECT_TRUE(result_folders(dir_ / "data", id).empty());
}

TEST_P(FarmService, ARunningJobsProgressIsSeenFromAnotherNode) {
  Node& b = node("node-b", 10.0, 0.1);
  const std::string id = b.submit(slow_image_job(800));
  Node& a = node("node-a", 10.0, 0.1);
  // Its holder (whichever node's worker claimed it first) stores progress with each heartbeat; the other node reads
  // it from the row.
  const auto running = [](const proto::JobStatus& s) { return s.state != proto::JobState::kQueued && s.progress > 0; };
  const std::string holder = a.wait(id, running).node;
  ASSERT_TRUE(holder == "node-a" || holder == "node-b") << holder;
  Node& other = holder == "node-a" ? b : a;
  const proto::JobStatus seen = other.wait(id, running);
  EXPECT_EQ(seen.node, holder);
  EXPECT_GT(seen.progress, 0);
  a.service->remove(id);
}

TEST_P(FarmService, TheSameIdempotencyKeyOnTwoNodesAtOnceMakesOneJob) {
  Node& a = node("node-a");
  Node& b = node("node-b");
  const std::string body = image_job().dump();
  constexpr int kKeys = 8;
  for (int k = 0; k < kKeys; ++k) {
    const std::string key = "farm-key-" + std::to_string(k);
    server::SubmitResult ra;
    server::SubmitResult rb;
    std::barrier together(2);
    std::thread ta([&] {
      together.arrive_and_wait();
      ra = a.service->submit(body, key);
    });
    std::thread tb([&] {
      together.arrive_and_wait();
      rb = b.service->submit(body, key);
    });
    ta.join();
    tb.join();
    EXPECT_EQ(ra.status.id, rb.status.id) << key;
    EXPECT_NE(ra.replayed, rb.replayed) << key;  // exactly one of them made the job
  }
  server::ListQuery all;
  all.limit = 100;
  EXPECT_EQ(store_->list(all).size(), static_cast<std::size_t>(kKeys));
}

TEST_P(FarmService, ACleanShutdownReleasesItsLeasesAndLeavesTheRegistry) {
  auto a = std::make_unique<Node>(db_->open(), dir_ / "data", "node-a", 10.0, 0.2);
  const std::string id = a->submit(slow_image_job(400));
  a->wait_state(id, proto::JobState::kRunning);
  ASSERT_EQ(store_->nodes().size(), 1u);
  a->service->shutdown(0.0);
  const auto row = store_->get(id);
  ASSERT_TRUE(row);
  EXPECT_EQ(row->state, proto::JobState::kQueued);
  EXPECT_EQ(row->attempts, 0);  // a release gives the attempt back
  EXPECT_TRUE(store_->nodes().empty());
  a.reset();
  Node& b = node("node-b");
  const proto::JobStatus done = b.wait_state(id, proto::JobState::kSucceeded);
  EXPECT_EQ(done.attempts, 1);
  EXPECT_EQ(done.node, "node-b");
}

TEST(PostgresFarm, ADatabaseRestartUnderLoadLosesNothing) {
  const fs::path dir = test_folder();
  PgPrivateCluster cluster(dir / "pg");
  PgTestDatabase db(cluster.url());
  const std::string migrate = std::string(TEXWARPD_BINARY) + " --store '" + db.url() + "' --migrate --data-dir " +
                              (dir / "data").string() + " > " + (dir / "migrate.log").string() + " 2>&1";
  ASSERT_EQ(std::system(migrate.c_str()), 0);
  ServerProcess server(dir / "data", {"--store", db.url(), "--threads-per-job", "1", "--workers", "2", "--lease-s",
                                      "10", "--heartbeat-s", "0.5", "--poll-ms", "50"});
  std::vector<std::string> ids;
  ids.push_back(submit_job(server.port(), slow_image_job(500)).json()["id"]);
  for (int i = 0; i < 5; ++i) ids.push_back(submit_job(server.port(), image_job()).json()["id"]);
  wait_for_state(server.port(), ids[0], "running", 30);
  cluster.pause();
  // Meanwhile: reads and writes answer 503 store-unavailable with Retry-After; the probes still answer.
  const HttpReply read = http_request(server.port(), "GET", "/v1/jobs/" + ids[0]);
  EXPECT_TRUE(is_problem(read, 503, "store-unavailable")) << read.body;
  EXPECT_EQ(read.header("retry-after"), "2");
  EXPECT_THAT(read.body, ::testing::Not(::testing::HasSubstr(db.url())));
  EXPECT_TRUE(is_problem(submit_job(server.port(), image_job()), 503, "store-unavailable"));
  EXPECT_EQ(http_request(server.port(), "GET", "/livez").status, 200);
  EXPECT_EQ(http_request(server.port(), "GET", "/readyz").status, 503);
  std::this_thread::sleep_for(std::chrono::seconds(2));
  cluster.resume();
  // After: every job ends succeeded, once (no lease expired: the outage was shorter than --lease-s), none added.
  for (const auto& id : ids) {
    const nlohmann::json s = wait_for_job(server.port(), id, 120);
    EXPECT_EQ(s["state"], "succeeded") << s.dump();
    EXPECT_EQ(s["attempts"], 1) << s.dump();
    EXPECT_EQ(result_folders(dir / "data", id), std::vector<std::string>{id + ".1"});
  }
  EXPECT_EQ(http_request(server.port(), "GET", "/v1/jobs").json()["jobs"].size(), ids.size());
  EXPECT_THAT(server.log(), ::testing::HasSubstr("the job store is unavailable"));
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_exit(30), 0);
  fs::remove_all(dir / "data");
}

// The store took a job's end but its reply was lost: the worker's retry is fenced (the job is no longer running).
// The job is succeeded in the store and names this run's folder, so the folder stays and serves its files (it was
// removed as a fenced run's: a succeeded job without its result; PostgresFarm.ADatabaseRestartUnderLoadLosesNothing
// saw it once under CI's load).
TEST_P(FarmService, AnEndWhoseReplyWasLostKeepsTheResultItRecorded) {
  nodes_.push_back(
      std::make_unique<Node>(std::make_unique<LostFirstFinishReply>(db_->open()), dir_ / "data", "node-a", 10.0, 0.2));
  Node& a = *nodes_.back();
  const std::string id = a.submit(image_job());
  const proto::JobStatus done = a.wait_state(id, proto::JobState::kSucceeded);
  EXPECT_EQ(done.attempts, 1);
  const auto row = store_->get(id);
  ASSERT_TRUE(row);
  EXPECT_EQ(row->result_folder, id + ".1");
  // The store says succeeded as soon as the first write is in; the worker retries 50 ms later and settles the
  // folder's fate then (or when its heartbeat finds the lease gone, 0.2 s): give it twenty times that.
  std::this_thread::sleep_for(std::chrono::seconds(1));
  EXPECT_EQ(result_folders(dir_ / "data", id), std::vector<std::string>{id + ".1"});
  std::string media_type;
  std::string sha256;
  EXPECT_TRUE(fs::exists(a.service->result_file(id, "warped.png", &media_type, &sha256)));
  EXPECT_THAT(a.metrics.render({}), ::testing::HasSubstr("texwarpd_jobs_fenced_total 0\n"));
}

INSTANTIATE_TEST_SUITE_P(Sqlite, FarmService, ::testing::Values(StoreBackend::kSqlite),
                         [](const auto&) { return std::string("sqlite"); });
// Needs the test cluster (CTest's `postgres` fixture): the test names start with "Postgres".
INSTANTIATE_TEST_SUITE_P(Postgres, FarmService, ::testing::Values(StoreBackend::kPostgres),
                         [](const auto&) { return std::string("postgresql"); });

}  // namespace
}  // namespace texwarp::testing
