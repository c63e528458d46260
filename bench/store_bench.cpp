// texwarp_bench_store: the latency of JobStore::claim (the farm's dispatch query) on SQLite and on PostgreSQL, with
// 0 and 100 000 finished jobs in the table, each claim a durable write (SQLite synchronous=FULL; PostgreSQL on a
// private cluster with fsync on), and of the claim's read alone (claim_read: the index walk that picks the job,
// without the write and its flush). Google Benchmark; p50_us and p99_us are the calls' own percentiles.
//
// Usage: texwarp_bench_store [--benchmark_repetitions=N] [--benchmark_filter=...] (other Google Benchmark flags)
//        Environment: TEXWARP_BENCH_DIR (default: the temp folder) holds the SQLite files and the cluster.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <pqxx/pqxx>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "pg_test_cluster.hpp"
#include "texwarp/server/postgres_job_store.hpp"
#include "texwarp/server/sqlite_connection.hpp"
#include "texwarp/server/sqlite_job_store.hpp"

namespace texwarp::bench {
namespace {

namespace fs = std::filesystem;
using server::JobStore;

constexpr int kClaimsPerRun = 1000;
// A finished row as big as a small real one: the job JSON and its manifest.
const std::string kSpec = R"({"kind": "image", "image": {"input": "blob:sha256:)" + std::string(64, 'a') +
                          R"(", "features": [)" + std::string(200, ' ') + "]}}";

enum class Backend { kSqlite, kPostgres };

// One store with `finished` finished rows, and a way to put kClaimsPerRun fresh queued jobs in front of it.
struct StoreUnderTest {
  std::unique_ptr<JobStore> store;
  std::function<void()> reset;       // removes what the last run claimed, queues kClaimsPerRun jobs
  std::function<void()> claim_read;  // the claim's SELECT alone, on a connection of its own
};

// The claim's choice of job, as the stores write it (SQLite names its index; PostgreSQL locks the row it picks).
constexpr const char* kSqliteClaimRead =
    "SELECT seq FROM jobs INDEXED BY jobs_claim WHERE state = 'queued' ORDER BY priority DESC, seq LIMIT 1";
constexpr const char* kPostgresClaimRead =
    "SELECT seq FROM jobs WHERE state = 'queued' ORDER BY priority DESC, seq LIMIT 1 FOR UPDATE SKIP LOCKED";

fs::path bench_dir() {
  const char* env = std::getenv("TEXWARP_BENCH_DIR");
  return (env != nullptr && *env != '\0' ? fs::path(env) : fs::temp_directory_path()) /
         ("texwarp-bench-store-" + std::to_string(::getpid()));
}

std::vector<server::NewJob> queued_jobs(int run) {
  std::vector<server::NewJob> jobs;
  for (int i = 0; i < kClaimsPerRun; ++i) {
    server::NewJob j;
    j.id = "q" + std::to_string(run) + "-" + std::to_string(i);
    j.spec_json = kSpec;
    j.body_sha256 = "sha";
    j.priority = i % 3;
    j.labels = {{"team", "fx"}};
    j.created_ms = 1;
    jobs.push_back(std::move(j));
  }
  return jobs;
}

// Everything the benchmarks made, removed at the end of main().
struct World {
  std::unique_ptr<testing::PgPrivateCluster> cluster;
  std::vector<std::unique_ptr<testing::PgTestDatabase>> databases;
  std::map<std::pair<Backend, int>, StoreUnderTest> stores;
};
World* world = nullptr;

StoreUnderTest make_sqlite(int finished) {
  const fs::path file = bench_dir() / ("jobs-" + std::to_string(finished) + ".sqlite3");
  fs::create_directories(file.parent_path());
  auto store = std::make_unique<server::SqliteJobStore>(file);
  {
    server::SqliteConnection db(file);
    db.exec("BEGIN");
    auto insert = db.prepare(
        "INSERT INTO jobs(id, name, kind, state, progress, attempts, created_ms, started_ms, finished_ms, spec, "
        "body_sha256, result, result_folder, node_id, lease_epoch) "
        "VALUES (?1, '', 'image', 'succeeded', 100, 1, ?2, ?2, ?2, ?3, 'sha', '{\"files\": []}', ?1 || '.1', 'n0', 1)");
    for (int i = 0; i < finished; ++i) {
      insert.bind(1, "f" + std::to_string(i)).bind(2, std::int64_t{i}).bind(3, kSpec);
      insert.step();
      insert.reset();
    }
    db.exec("COMMIT");
    db.exec("ANALYZE");
  }
  auto* raw = store.get();
  auto run = std::make_shared<int>(0);
  auto reader = std::make_shared<server::SqliteConnection>(file);
  auto read = std::make_shared<server::SqliteStatement>(reader->prepare(kSqliteClaimRead));
  return {std::move(store),
          [raw, file, run] {
            {
              server::SqliteConnection db(file);
              db.exec("DELETE FROM jobs WHERE state = 'running'");
            }
            raw->insert_batch(queued_jobs((*run)++));
          },
          [reader, read] {
            if (!read->step()) throw std::runtime_error("nothing queued");
            read->reset();
          }};
}

StoreUnderTest make_postgres(int finished) {
  if (!world->cluster) {
    world->cluster = std::make_unique<testing::PgPrivateCluster>(bench_dir() / "pg", 0, /*durable=*/true);
  }
  world->databases.push_back(std::make_unique<testing::PgTestDatabase>(world->cluster->url()));
  const std::string url = world->databases.back()->url();
  auto store = std::make_unique<server::PostgresJobStore>(url, /*migrate=*/true);
  {
    pqxx::connection c(url);
    pqxx::work tx(c);
    tx.exec_params(
        "INSERT INTO jobs(id, name, kind, state, progress, attempts, created_ms, started_ms, finished_ms, spec, "
        "body_sha256, result, result_folder, node_id, lease_epoch) "
        "SELECT 'f' || i, '', 'image', 'succeeded', 100, 1, i, i, i, $1, 'sha', '{\"files\": []}', 'f' || i || '.1', "
        "'n0', 1 FROM generate_series(1, $2) AS i",
        kSpec, finished);
    tx.commit();
    pqxx::nontransaction vacuum(c);
    vacuum.exec("VACUUM ANALYZE jobs");
  }
  auto* raw = store.get();
  auto run = std::make_shared<int>(0);
  auto reader = std::make_shared<pqxx::connection>(url);
  reader->prepare("claim_read", kPostgresClaimRead);
  return {std::move(store),
          [raw, url, run] {
            {
              pqxx::connection c(url);
              pqxx::nontransaction tx(c);
              tx.exec("DELETE FROM jobs WHERE state = 'running'");
            }
            raw->insert_batch(queued_jobs((*run)++));
          },
          [reader] {
            pqxx::work tx(*reader);  // rolled back: the row lock goes, nothing is written
            if (tx.exec_prepared("claim_read").empty()) throw std::runtime_error("nothing queued");
          }};
}

StoreUnderTest& store_for(Backend backend, int finished) {
  auto& slot = world->stores[{backend, finished}];
  if (!slot.store) slot = backend == Backend::kSqlite ? make_sqlite(finished) : make_postgres(finished);
  return slot;
}

void claim_latency(benchmark::State& state, Backend backend, int finished) {
  StoreUnderTest& s = store_for(backend, finished);
  s.reset();
  std::vector<double> micros;
  micros.reserve(kClaimsPerRun);
  std::int64_t now = 1'000'000;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    const auto lease = s.store->claim("bench-node", ++now, 30'000);
    micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
    if (!lease) {
      state.SkipWithError("the queue ran dry");
      break;
    }
    benchmark::DoNotOptimize(lease->epoch);
  }
  std::sort(micros.begin(), micros.end());
  if (!micros.empty()) {
    state.counters["p50_us"] = micros[micros.size() / 2];
    state.counters["p99_us"] = micros[std::min(micros.size() - 1, micros.size() * 99 / 100)];
  }
}

void claim_read_latency(benchmark::State& state, Backend backend, int finished) {
  StoreUnderTest& s = store_for(backend, finished);
  s.reset();
  std::vector<double> micros;
  micros.reserve(kClaimsPerRun);
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    s.claim_read();
    micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(micros.begin(), micros.end());
  state.counters["p50_us"] = micros[micros.size() / 2];
  state.counters["p99_us"] = micros[std::min(micros.size() - 1, micros.size() * 99 / 100)];
}

}  // namespace
}  // namespace texwarp::bench

int main(int argc, char** argv) {
  using texwarp::bench::Backend;
  texwarp::bench::World world;
  texwarp::bench::world = &world;
  benchmark::Initialize(&argc, argv);
  for (const auto& [backend, name] :
       {std::pair{Backend::kSqlite, "sqlite"}, std::pair{Backend::kPostgres, "postgresql"}}) {
    for (const int finished : {0, 100'000}) {
      using Measure = void (*)(benchmark::State&, Backend, int);
      for (const auto& [kind, function] :
           {std::pair<const char*, Measure>{"claim", texwarp::bench::claim_latency},
            std::pair<const char*, Measure>{"claim_read", texwarp::bench::claim_read_latency}}) {
        benchmark::RegisterBenchmark((std::string(kind) + "/" + name + "/finished:" + std::to_string(finished)).c_str(),
                                     function, backend, finished)
            ->Iterations(texwarp::bench::kClaimsPerRun)
            ->Repetitions(3)
            ->UseRealTime()
            ->Unit(benchmark::kMicrosecond);
      }
    }
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  world.stores.clear();
  world.databases.clear();
  world.cluster.reset();
  std::error_code ignored;
  std::filesystem::remove_all(texwarp::bench::bench_dir(), ignored);
  return 0;
}
