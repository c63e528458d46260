// The farm from outside: three real texwarpd nodes on one PostgreSQL database and one shared data folder, on
// loopback, with short leases. Jobs run exactly once; a node killed or stopped mid-job loses nothing and can never
// overwrite the winner's result (fencing); a database restart loses nothing; cancel and idempotency work across nodes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <latch>
#include <set>
#include <sstream>
#include <thread>

#include "api_helpers.hpp"
#include "farm_nodes.hpp"
#include "pausable_proxy.hpp"
#include "pg_test_cluster.hpp"
#include "served_results.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The job is succeeded and every node serves the same files, each matching the manifest; returns them.
std::map<std::string, std::string> expect_served_alike(FarmNodes& farm, const std::string& id) {
  std::map<std::string, std::string> first;
  for (int i = 0; i < farm.size(); ++i) {
    if (!farm.up(i)) continue;
    const ServedFiles files = fetch_result_files(farm.port(i), id);
    EXPECT_EQ(files.bad, 0) << farm.node_id(i) << " " << id;
    if (first.empty()) {
      first = files.bytes;
    } else {
      EXPECT_TRUE(files.bytes == first) << farm.node_id(i) << " serves other files for " << id;
    }
  }
  EXPECT_FALSE(first.empty()) << id;
  return first;
}

// Submits to the node and returns the new job's id (the test fails on anything but 202).
std::string submit(unsigned short port, const nlohmann::json& job) {
  const HttpReply r = submit_job(port, job);
  EXPECT_EQ(r.status, 202) << r.body;
  return r.json().value("id", "");
}

// Waits until the job runs with progress ≥ min_progress and returns the index of the node that holds it.
int holder_of(FarmNodes& farm, const std::string& id, int min_progress) {
  const nlohmann::json s = wait_for_state(farm.port(0), id, "running", 120, min_progress);
  const int holder = farm.index_of(s.value("node", ""));
  EXPECT_GE(holder, 0) << "no node of the farm holds it: " << s.dump();
  return holder;
}

// The first of the node's JSON log lines about `job` whose "msg" starts with one of `messages`, waiting up to
// timeout_s for it (null when none came).
nlohmann::json await_log_event(FarmNodes& farm, int i, const std::string& job, const std::vector<std::string>& messages,
                               double timeout_s) {
  const auto t0 = Clock::now();
  do {
    std::istringstream lines(farm.logs(i));
    for (std::string line; std::getline(lines, line);) {
      nlohmann::json e = nlohmann::json::parse(line, nullptr, false);
      if (!e.is_object() || e.value("job", "") != job) continue;
      for (const auto& m : messages) {
        if (e.value("msg", "").rfind(m, 0) == 0) return e;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  } while (seconds_since(t0) < timeout_s);
  return nullptr;
}

TEST(Farm, JobsSubmittedRoundRobinRunExactlyOnceAndEveryNodeServesThem) {
  const fs::path dir = test_folder();
  PgTestDatabase db;
  FarmNodes farm(dir / "data", db.url(), 3);

  // Every node sees the three, alive, each with the pid of its process.
  for (int i = 0; i < 3; ++i) {
    const HttpReply r = http_request(farm.port(i), "GET", "/v1/nodes");
    ASSERT_EQ(r.status, 200) << r.body;
    const nlohmann::json listed = r.json();
    std::map<std::string, nlohmann::json> by_id;
    for (const auto& n : listed["nodes"]) by_id[n.value("id", "")] = n;
    ASSERT_EQ(by_id.size(), 3u) << r.body;
    for (int k = 0; k < 3; ++k) {
      const nlohmann::json& n = by_id[farm.node_id(k)];
      EXPECT_EQ(n.value("alive", false), true) << n.dump();
      EXPECT_EQ(n.value("pid", 0), farm.node(k).pid()) << n.dump();
      EXPECT_EQ(n.value("workers", 0), 1) << n.dump();
      EXPECT_EQ(n.value("address", ""), "127.0.0.1:" + std::to_string(farm.port(k))) << n.dump();
    }
  }

  EXPECT_THAT(http_request(farm.port(1), "GET", "/metrics").body, HasSubstr("\ntexwarpd_nodes_alive 3\n"));

  std::vector<std::string> ids;
  ids.reserve(30);
  for (int i = 0; i < 30; ++i) ids.push_back(submit(farm.port(i % 3), i % 3 == 2 ? mesh_job() : image_job()));
  std::map<std::string, int> ran_on;
  for (int i = 0; i < 30; ++i) {
    const std::string& id = ids[static_cast<std::size_t>(i)];
    const nlohmann::json s = wait_for_job(farm.port((i + 1) % 3), id, 300);
    ASSERT_EQ(s.value("state", ""), "succeeded") << s.dump();
    EXPECT_EQ(s.value("attempts", 0), 1) << s.dump();
    ++ran_on[s.value("node", "")];
    EXPECT_THAT(published_result_folders(farm.data_dir(), id), ElementsAre(id + ".1"));
    EXPECT_THAT(temp_result_folders(farm.data_dir(), id), ElementsAre());
    expect_served_alike(farm, id);
  }
  for (const auto& [node, n] : ran_on) {
    EXPECT_GE(farm.index_of(node), 0) << node;
    std::printf("%s ran %d jobs\n", node.c_str(), n);
  }
  EXPECT_GE(ran_on.size(), 2u) << "one node ran every job";
  for (int i = 0; i < 3; ++i) EXPECT_EQ(list_all_jobs(farm.port(i)).size(), 30u);
  fs::remove_all(dir);
}

TEST(Farm, AJobOfANodeKilledMidRunFinishesOnAnotherAfterTheLease) {
  const fs::path dir = test_folder();
  PgTestDatabase db;
  FarmNodes farm(dir / "data", db.url(), 3);
  const std::string id = submit(farm.port(0), slow_image_job(500));
  const int holder = holder_of(farm, id, 5);
  ASSERT_GE(holder, 0);

  const auto killed_at = Clock::now();
  farm.kill(holder);
  const int other = (holder + 1) % 3;
  const nlohmann::json s = wait_for_job(farm.port(other), id, 300);
  const double recovery_s = seconds_since(killed_at);
  ASSERT_EQ(s.value("state", ""), "succeeded") << s.dump();
  EXPECT_EQ(s.value("attempts", 0), 2) << s.dump();
  EXPECT_NE(s.value("node", ""), farm.node_id(holder));
  EXPECT_GE(farm.index_of(s.value("node", "")), 0) << s.dump();
  EXPECT_THAT(published_result_folders(farm.data_dir(), id), ElementsAre(id + ".2"));
  expect_served_alike(farm, id);
  const double rerun_s = static_cast<double>(epoch_ms(s["finished_at"]) - epoch_ms(s["started_at"])) / 1000;
  std::printf("recovery after kill -9 (kill → succeeded): %.2f s, of which the second run %.2f s (lease 2 s)\n",
              recovery_s, rerun_s);
  fs::remove_all(dir);
}

TEST(Farm, ANodeStoppedPastItsLeaseRecordsNothingAndTheWinnersResultIsServed) {
  const fs::path dir = test_folder();
  PgTestDatabase db;
  FarmNodes farm(dir / "data", db.url(), 3);
  const std::string id = submit(farm.port(0), slow_image_job(500));
  const int stopped = holder_of(farm, id, 5);
  ASSERT_GE(stopped, 0);

  farm.node(stopped).signal(SIGSTOP);
  const int other = (stopped + 1) % 3;
  const nlohmann::json won = wait_for_job(farm.port(other), id, 300);
  ASSERT_EQ(won.value("state", ""), "succeeded") << won.dump();
  EXPECT_EQ(won.value("attempts", 0), 2) << won.dump();
  const std::string winner = won.value("node", "");
  EXPECT_NE(winner, farm.node_id(stopped));
  const ServedFiles winners_files = fetch_result_files(farm.port(other), id);

  farm.node(stopped).signal(SIGCONT);
  // The stopped node goes on where it was: its next heartbeat learns that the lease is gone ("lease_lost": the run
  // stops, nothing recorded), or, had its run ended first, the store refuses the outcome (job_fenced).
  const nlohmann::json refused = await_log_event(farm, stopped, id, {"lease_lost", "job_fenced"}, 300);
  EXPECT_TRUE(refused.is_object()) << farm.logs(stopped);
  std::printf("the stopped node, continued: %s\n", refused.dump().c_str());

  for (int i = 0; i < 3; ++i) {
    const nlohmann::json s = job_status(farm.port(i), id);
    EXPECT_EQ(s.value("state", ""), "succeeded") << s.dump();
    EXPECT_EQ(s.value("node", ""), winner) << s.dump();
    EXPECT_EQ(s.value("attempts", 0), 2) << s.dump();
    EXPECT_EQ(s["finished_at"], won["finished_at"]) << s.dump();
    const ServedFiles files = fetch_result_files(farm.port(i), id);
    EXPECT_EQ(files.bad, 0);
    EXPECT_TRUE(files.bytes == winners_files.bytes) << farm.node_id(i) << " serves other files";
  }
  EXPECT_THAT(published_result_folders(farm.data_dir(), id), ElementsAre(id + ".2"));  // the loser's is not published
  EXPECT_TRUE(await_log_event(farm, stopped, id, {"job stopped", "job_fenced"}, 120).is_object());
  EXPECT_THAT(temp_result_folders(farm.data_dir(), id), ElementsAre());
  // The node is still a working member of the farm.
  const std::string next = submit(farm.port(stopped), image_job());
  EXPECT_EQ(wait_for_job(farm.port(stopped), next, 120).value("state", ""), "succeeded");
  fs::remove_all(dir);
}

TEST(Farm, ANodeCutOffFromTheDatabasePastItsLeaseHasItsFinishedResultRefused) {
  // node-1 reaches the database through a relay the test can pause: cut off, it cannot renew its lease nor learn
  // that it lost it, so it finishes its run, publishes its folder and hangs in recording the end, while node-2 or
  // node-3 reclaims the job and finishes it. When the relay resumes, node-1's outcome meets the new epoch: refused.
  const fs::path dir = test_folder();
  const unsigned short pg_port = free_loopback_port();
  PgPrivateCluster pg(dir / "pg", pg_port);
  PausableProxy relay(pg_port);
  std::string via_relay = pg.url();
  via_relay.replace(via_relay.find(":" + std::to_string(pg_port) + "/"), std::to_string(pg_port).size() + 2,
                    ":" + std::to_string(relay.port()) + "/");
  FarmNodes farm(dir / "data", via_relay, 1);
  const std::string id = submit(farm.port(0), slow_image_job(400));
  ASSERT_EQ(wait_for_state(farm.port(0), id, "running", 120, 5).value("node", ""), farm.node_id(0));
  farm.add(pg.url());
  farm.add(pg.url());

  relay.pause();
  const nlohmann::json won = wait_for_job(farm.port(1), id, 300);
  ASSERT_EQ(won.value("state", ""), "succeeded") << won.dump();
  EXPECT_EQ(won.value("attempts", 0), 2) << won.dump();
  const std::string winner = won.value("node", "");
  EXPECT_TRUE(winner == farm.node_id(1) || winner == farm.node_id(2)) << won.dump();
  const ServedFiles winners_files = fetch_result_files(farm.port(1), id);
  const auto t0 = Clock::now();
  while (!fs::exists(farm.data_dir() / "results" / (id + ".1")) && seconds_since(t0) < 300) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(fs::exists(farm.data_dir() / "results" / (id + ".1"))) << "node-1 never published its run";

  relay.resume();
  // Its heartbeat may learn of the lost lease first (lease_lost), but its run is past the last check: its finish
  // reaches the store and is refused.
  const nlohmann::json fenced = await_log_event(farm, 0, id, {"job_fenced"}, 120);
  EXPECT_EQ(fenced.value("msg", ""), "job_fenced") << farm.logs(0);
  EXPECT_EQ(fenced.value("epoch", 0), 1) << fenced.dump();
  EXPECT_THAT(published_result_folders(farm.data_dir(), id), ElementsAre(id + ".2"));  // node-1 removed its own
  for (int i = 0; i < 3; ++i) {
    const nlohmann::json s = job_status(farm.port(i), id);
    EXPECT_EQ(s.value("node", ""), winner) << s.dump();
    EXPECT_EQ(s["finished_at"], won["finished_at"]) << s.dump();
    EXPECT_TRUE(fetch_result_files(farm.port(i), id).bytes == winners_files.bytes) << farm.node_id(i);
  }
  const HttpReply metrics = http_request(farm.port(0), "GET", "/metrics");
  EXPECT_THAT(metrics.body, HasSubstr("\ntexwarpd_jobs_fenced_total 1\n"));
  fs::remove_all(dir);
}

TEST(Farm, TheDatabaseRestartedUnderLoadLosesNothing) {
  const fs::path dir = test_folder();
  PgPrivateCluster pg(dir / "pg");
  FarmNodes farm(dir / "data", pg.url(), 3);
  std::vector<std::string> ids;
  ids.reserve(3 + 9);
  for (int i = 0; i < 3; ++i) ids.push_back(submit(farm.port(i), slow_image_job(300)));
  for (int i = 0; i < 9; ++i) ids.push_back(submit(farm.port(i % 3), i % 3 == 1 ? mesh_job() : image_job()));
  wait_for_state(farm.port(0), ids[0], "running", 120, 1);

  pg.pause();
  // While it is down: not ready, and a submission is refused with a time to come back, never half-accepted.
  const auto down_at = Clock::now();
  HttpReply ready;
  while (seconds_since(down_at) < 30) {
    ready = http_request(farm.port(1), "GET", "/readyz");
    if (ready.status == 503) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(ready.status, 503) << ready.body;
  const HttpReply refused = submit_job(farm.port(2), image_job());
  EXPECT_TRUE(is_problem(refused, 503, "store-unavailable"));
  EXPECT_FALSE(refused.header("retry-after").empty());
  std::this_thread::sleep_for(std::chrono::seconds(3));  // past the 2 s leases
  pg.resume();

  for (int i = 0; i < 3; ++i) {
    const auto t0 = Clock::now();
    HttpReply r;
    while (seconds_since(t0) < 60) {
      r = http_request(farm.port(i), "GET", "/readyz");
      if (r.status == 200) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    EXPECT_EQ(r.status, 200) << farm.node_id(i) << ": " << r.body;
  }
  for (const auto& id : ids) {
    const nlohmann::json s = wait_for_job(farm.port(0), id, 300);
    EXPECT_EQ(s.value("state", ""), "succeeded") << s.dump();
    EXPECT_EQ(published_result_folders(farm.data_dir(), id).size(), 1u) << id;
    expect_served_alike(farm, id);
  }
  std::set<std::string> listed;
  for (const auto& s : list_all_jobs(farm.port(1))) listed.insert(s.value("id", ""));
  EXPECT_EQ(listed, std::set<std::string>(ids.begin(), ids.end()));  // the refused submission made nothing
  fs::remove_all(dir);
}

TEST(Farm, ACancelSentToOneNodeStopsTheJobRunningOnAnother) {
  const fs::path dir = test_folder();
  PgTestDatabase db;
  FarmNodes farm(dir / "data", db.url(), 3);
  const std::string id = submit(farm.port(0), slow_image_job(900));
  const int holder = holder_of(farm, id, 1);
  ASSERT_GE(holder, 0);
  const int asked = (holder + 1) % 3;
  const auto t0 = Clock::now();
  const HttpReply r = http_request(farm.port(asked), "DELETE", "/v1/jobs/" + id);
  EXPECT_EQ(r.status, 202) << r.body;
  const nlohmann::json s = wait_for_state(farm.port((holder + 2) % 3), id, "canceled", 60);
  std::printf("canceled on %s through %s in %.2f s\n", farm.node_id(holder).c_str(), farm.node_id(asked).c_str(),
              seconds_since(t0));
  EXPECT_EQ(s.value("state", ""), "canceled") << s.dump();
  EXPECT_EQ(s.value("node", ""), farm.node_id(holder)) << s.dump();
  // The holder itself stopped the run and recorded its end.
  const nlohmann::json ended = await_log_event(farm, holder, id, {"job finished"}, 60);
  EXPECT_EQ(ended.value("state", ""), "canceled") << farm.logs(holder);
  EXPECT_THAT(published_result_folders(farm.data_dir(), id), ElementsAre());
  // The holder's worker is free again.
  const std::string next = submit(farm.port(holder), image_job());
  EXPECT_EQ(wait_for_job(farm.port(holder), next, 120).value("state", ""), "succeeded");
  fs::remove_all(dir);
}

TEST(Farm, TheSameIdempotencyKeySentToTwoNodesAtOnceMakesOneJob) {
  const fs::path dir = test_folder();
  PgTestDatabase db;
  FarmNodes farm(dir / "data", db.url(), 3);
  constexpr int kKeys = 10;
  std::set<std::string> ids;
  for (int k = 0; k < kKeys; ++k) {
    const std::string key = "farm-key-" + std::to_string(k);
    nlohmann::json job = image_job();
    job["name"] = key;
    std::latch go(2);
    HttpReply replies[2];
    std::thread threads[2];
    for (int t = 0; t < 2; ++t) {
      threads[t] = std::thread([&, t] {
        go.arrive_and_wait();
        replies[t] = submit_job(farm.port((k + t) % 3), job, {{"Idempotency-Key", key}});
      });
    }
    for (auto& t : threads) t.join();
    ASSERT_EQ(replies[0].status, 202) << replies[0].body;
    ASSERT_EQ(replies[1].status, 202) << replies[1].body;
    EXPECT_EQ(replies[0].json()["id"], replies[1].json()["id"]);
    EXPECT_EQ(
        (replies[0].header("idempotent-replayed") == "true") + (replies[1].header("idempotent-replayed") == "true"), 1)
        << key;
    ids.insert(replies[0].json().value("id", ""));
  }
  EXPECT_EQ(ids.size(), static_cast<std::size_t>(kKeys));
  EXPECT_EQ(list_all_jobs(farm.port(2)).size(), static_cast<std::size_t>(kKeys));
  for (const auto& id : ids) EXPECT_EQ(wait_for_job(farm.port(0), id, 300).value("state", ""), "succeeded");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace texwarp::testing
