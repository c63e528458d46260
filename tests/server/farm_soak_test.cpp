// The farm soak (ctest -L soak; TEXWARP_SOAK_MINUTES, default 20; TEXWARP_SOAK_SEED): three texwarpd nodes on one
// PostgreSQL database run a stream of mixed image and mesh jobs while nodes are killed with SIGKILL at random and
// restarted in place. Counts lost, duplicated and corrupted results, which must all be 0.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>

#include "api_helpers.hpp"
#include "farm_nodes.hpp"
#include "pg_test_cluster.hpp"
#include "served_results.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double env_number(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? std::strtod(v, nullptr) : fallback;
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

bool terminal(const std::string& state) { return state == "succeeded" || state == "failed" || state == "canceled"; }

// One of the soak's jobs: mostly small image jobs of varied output sizes, some slower ones, some mesh jobs.
nlohmann::json random_job(std::mt19937& rng, int n) {
  const int pick = std::uniform_int_distribution<int>(0, 9)(rng);
  nlohmann::json job = pick < 3   ? mesh_job()
                       : pick < 5 ? slow_image_job(std::uniform_int_distribution<int>(150, 300)(rng))
                                  : image_job(std::uniform_int_distribution<int>(32, 160)(rng));
  job["name"] = "soak " + std::to_string(n);
  return job;
}

TEST(FarmSoak, NodesKilledAtRandomLoseDuplicateAndCorruptNothing) {
  const double minutes = env_number("TEXWARP_SOAK_MINUTES", 20);
  const auto seed = static_cast<unsigned>(env_number("TEXWARP_SOAK_SEED", static_cast<double>(std::random_device{}())));
  std::printf("farm soak: 3 nodes, %.1f minutes, seed %u\n", minutes, seed);
  std::fflush(stdout);
  std::mt19937 rng(seed);
  const fs::path dir = test_folder();
  PgTestDatabase db;
  FarmOptions options;
  options.max_attempts = 50;  // kills are the test's, not the jobs' fault: a job is never failed for them
  FarmNodes farm(dir / "data", db.url(), 3, options);

  std::map<std::string, std::string> id_of_key;  // Idempotency-Key → the job it made
  std::set<std::string> outstanding;
  std::vector<Clock::time_point> restart_at(3, Clock::time_point::max());
  int kills = 0;
  int submit_retries = 0;
  auto next_kill = Clock::now() + std::chrono::seconds(5);
  auto next_poll = Clock::now();
  const auto start = Clock::now();
  const auto random_up_node = [&]() {
    std::vector<int> up;
    for (int i = 0; i < 3; ++i) {
      if (farm.up(i)) up.push_back(i);
    }
    return up.empty() ? -1 : up[std::uniform_int_distribution<std::size_t>(0, up.size() - 1)(rng)];
  };

  while (seconds_since(start) < minutes * 60) {
    const auto now = Clock::now();
    for (int i = 0; i < 3; ++i) {
      if (restart_at[static_cast<std::size_t>(i)] <= now) {
        farm.restart(i);
        restart_at[static_cast<std::size_t>(i)] = Clock::time_point::max();
      }
    }
    if (now >= next_kill) {
      int up = 0;
      for (int i = 0; i < 3; ++i) up += farm.up(i);
      if (up >= 2) {  // at least one node stays up
        const int victim = random_up_node();
        farm.kill(victim);
        ++kills;
        restart_at[static_cast<std::size_t>(victim)] =
            now + std::chrono::milliseconds(std::uniform_int_distribution<int>(500, 5000)(rng));
      }
      next_kill = now + std::chrono::milliseconds(std::uniform_int_distribution<int>(3000, 30000)(rng));
    }
    if (now >= next_poll) {
      for (auto it = outstanding.begin(); it != outstanding.end();) {
        const int node = random_up_node();
        const nlohmann::json s = job_status(farm.port(node), *it);
        it = s.is_object() && terminal(s.value("state", "")) ? outstanding.erase(it) : std::next(it);
      }
      next_poll = now + std::chrono::milliseconds(500);
    }
    if (outstanding.size() < 8) {
      // A fresh key per job; a refused or broken submission is sent again with the same key to another node.
      const std::string key = "soak-" + std::to_string(seed) + "-" + std::to_string(id_of_key.size());
      const nlohmann::json job = random_job(rng, static_cast<int>(id_of_key.size()));
      for (int attempt = 0; attempt < 100; ++attempt) {
        const HttpReply r = submit_job(farm.port(random_up_node()), job, {{"Idempotency-Key", key}});
        if (r.status == 202) {
          id_of_key[key] = r.json().value("id", "");
          outstanding.insert(id_of_key[key]);
          break;
        }
        ++submit_retries;
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
      ASSERT_EQ(id_of_key.count(key), 1u) << "job " << key << " was never accepted";
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  for (int i = 0; i < 3; ++i) {
    if (!farm.up(i)) farm.restart(i);
  }

  // The reckoning: every accepted job succeeded once, with one result folder whose files match the manifest.
  int lost = 0;
  int duplicated = 0;
  int corrupted = 0;
  std::map<int, int> attempts;
  std::set<std::string> accepted;
  for (const auto& [key, id] : id_of_key) accepted.insert(id);
  duplicated += static_cast<int>(id_of_key.size() - accepted.size());  // two keys, one job: never expected
  for (const auto& id : accepted) {
    const nlohmann::json known = job_status(farm.port(0), id);
    const nlohmann::json s = known.contains("state") ? wait_for_job(farm.port(0), id, 600) : known;
    if (s.value("state", "") != "succeeded") {
      ++lost;
      ADD_FAILURE() << "lost: " << s.dump();
      continue;
    }
    ++attempts[s.value("attempts", 0)];
    const auto folders = published_result_folders(farm.data_dir(), id);
    if (folders.size() != 1) {
      ++duplicated;
      ADD_FAILURE() << id << " has " << folders.size() << " result folders";
    }
    const ServedFiles files = fetch_result_files(farm.port(std::uniform_int_distribution<int>(0, 2)(rng)), id);
    corrupted += files.bad > 0;
  }
  std::set<std::string> listed;
  const auto all = list_all_jobs(farm.port(1));
  for (const auto& s : all) listed.insert(s.value("id", ""));
  for (const auto& id : listed) {
    if (!accepted.count(id)) ++duplicated;  // a job nobody was told about: a submission stored twice
  }

  // Every run that recorded success logged it once ("job finished", state succeeded): two for one job would be a
  // job finished twice. Fenced runs and lost leases are counted for the record.
  std::map<std::string, int> successes;
  int fenced = 0;
  int leases_lost = 0;
  for (int i = 0; i < 3; ++i) {
    std::istringstream lines(farm.logs(i));
    for (std::string line; std::getline(lines, line);) {
      const nlohmann::json e = nlohmann::json::parse(line, nullptr, false);
      if (!e.is_object()) continue;
      const std::string msg = e.value("msg", "");
      if (msg == "job finished" && e.value("state", "") == "succeeded") ++successes[e.value("job", "")];
      fenced += msg == "job_fenced";
      leases_lost += msg.rfind("lease_lost", 0) == 0;
    }
  }
  for (const auto& [id, n] : successes) {
    if (n > 1) {
      ++duplicated;
      ADD_FAILURE() << id << " finished " << n << " times";
    }
  }

  std::printf("farm soak: %zu jobs in %.1f min (%.1f jobs/min), %d kills, %d submissions retried\n", accepted.size(),
              seconds_since(start) / 60, static_cast<double>(accepted.size()) / (seconds_since(start) / 60), kills,
              submit_retries);
  for (const auto& [n, count] : attempts) std::printf("  attempts %d: %d jobs\n", n, count);
  std::printf("  runs fenced: %d, leases lost: %d\n", fenced, leases_lost);
  std::printf("farm soak: lost %d, duplicated %d, corrupted %d\n", lost, duplicated, corrupted);
  EXPECT_EQ(lost, 0);
  EXPECT_EQ(duplicated, 0);
  EXPECT_EQ(corrupted, 0);
  EXPECT_GT(kills, 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace texwarp::testing
