// texwarpd as an operator runs it (the real server on loopback): the data folder's lock, a full disk (507 on
// submit, a job's end recorded once space returns, cancel and SIGTERM meanwhile), orphaned temporaries removed at
// start, /readyz "draining" during the shutdown grace, and OpenCL start-ups with several workers.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "api_helpers.hpp"
#include "raw_http.hpp"
#include "server_process.hpp"
#include "small_filesystem.hpp"
#include "test_jobs.hpp"
#include "test_time.hpp"
#include "texwarp/proto/base64.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using ::testing::HasSubstr;
using ::testing::Not;

struct Exit {
  int code = -1;  // -1: still running when the time ran out (then killed)
  std::string output;
};

// Runs texwarpd with these arguments (stdout and stderr together) and waits up to timeout_s for it to exit.
Exit run_texwarpd(const std::vector<std::string>& args, double timeout_s) {
  const fs::path out = test_folder("-run") / "output.txt";
  std::vector<std::string> strings = {TEXWARPD_BINARY};
  strings.insert(strings.end(), args.begin(), args.end());
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    std::vector<char*> argv;
    argv.reserve(strings.size() + 1);
    for (auto& s : strings) argv.push_back(s.data());
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  Exit e;
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (Clock::now() >= deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      status = -1;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (status != -1) e.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  std::ifstream in(out);
  std::stringstream text;
  text << in.rdbuf();
  e.output = text.str();
  return e;
}

// Waits until the server's log holds `text`; false when the time runs out.
bool wait_for_log(const ServerProcess& server, const std::string& text, double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(wait_seconds(timeout_s));
  while (Clock::now() < deadline) {
    if (server.log().find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

TEST(DataDirLock, ASecondServerOnTheSameFolderExitsTwoNamingTheFirst) {
  const fs::path dir = test_folder();
  ServerProcess first(dir / "data", {"--threads-per-job", "1"});
  const std::string id = submit_job(first.port(), slow_image_job(250)).json()["id"];
  wait_for_state(first.port(), id, "running", 30, 2);

  const Exit second =
      run_texwarpd({"--listen", "127.0.0.1:0", "--data-dir", (dir / "data").string(), "--device", "cpu"}, 20);
  EXPECT_EQ(second.code, 2) << second.output;
  EXPECT_THAT(second.output, HasSubstr("--data-dir " + (dir / "data").string() + " is in use by texwarpd (pid " +
                                       std::to_string(first.pid()) + "); stop it or use another folder"));

  // The first server's job was left alone: it runs on (never re-queued) and succeeds with its results.
  const nlohmann::json s = wait_for_job(first.port(), id);
  EXPECT_EQ(s["state"], "succeeded") << s.dump();
  EXPECT_EQ(s["attempts"], 1);
  EXPECT_EQ(http_request(first.port(), "GET", "/v1/jobs/" + id + "/result").status, 200);
  std::string pid;
  std::ifstream(dir / "data" / "texwarpd.lock") >> pid;
  EXPECT_EQ(pid, std::to_string(first.pid()));
}

TEST(DataDirLock, TheLockGoesWithTheProcess) {
  const fs::path dir = test_folder();
  {
    ServerProcess killed(dir / "data");
    killed.signal(SIGKILL);
    ASSERT_EQ(killed.wait_exit(10), 128 + SIGKILL);
  }
  ServerProcess next(dir / "data");  // fails the test when it does not come up
  EXPECT_EQ(http_request(next.port(), "GET", "/livez").status, 200);
}

TEST(ConfigFile, AMisspeltKeyIsAnErrorNamingIt) {
  const fs::path dir = test_folder();
  std::ofstream(dir / "typo.toml") << "workerz = 2\n";
  const Exit typo = run_texwarpd({"--config", (dir / "typo.toml").string(), "--data-dir", (dir / "data").string(),
                                  "--listen", "127.0.0.1:0", "--device", "cpu"},
                                 20);
  EXPECT_EQ(typo.code, 2) << typo.output;
  EXPECT_THAT(typo.output, HasSubstr("--config " + (dir / "typo.toml").string() + ": unknown key \"workerz\""));
  EXPECT_FALSE(fs::exists(dir / "data" / "jobs.sqlite3"));  // refused before anything was created

  std::ofstream(dir / "good.toml") << "workers = 2\n";
  ServerProcess server(dir / "data", {"--config", (dir / "good.toml").string()});
  EXPECT_EQ(http_request(server.port(), "GET", "/livez").status, 200);
}

class DiskFull : public ::testing::Test {
 protected:
  void SetUp() override {
    disk_ = std::make_unique<SmallFilesystem>(24ULL << 20);
    if (!disk_->available()) GTEST_SKIP() << disk_->why_not();
  }
  fs::path data() const { return disk_->path() / "data"; }

  std::unique_ptr<SmallFilesystem> disk_;
};

TEST_F(DiskFull, SubmitAnswers507WithRetryAfterAndReadyzSaysTheStoreFails) {
  ServerProcess server(data(), {"--threads-per-job", "1"});
  const HttpReply first = submit_job(server.port(), image_job());
  ASSERT_EQ(first.status, 202) << first.body;
  ASSERT_EQ(wait_for_job(server.port(), first.json()["id"])["state"], "succeeded");

  disk_->fill();
  // The same texture is stored already: only the job's row has to be written, and the store is full.
  const HttpReply refused = submit_job(server.port(), image_job());
  EXPECT_TRUE(is_problem(refused, 507, "insufficient-storage")) << refused.body;
  EXPECT_FALSE(refused.header("retry-after").empty());
  EXPECT_THAT(refused.json().value("detail", ""), HasSubstr("storage is full"));
  // A texture not stored yet fails on the blob's file instead: the same answer.
  nlohmann::json other = image_job();
  other["image"]["base64"] = proto::base64_encode(test_png(80));
  const HttpReply other_refused = submit_job(server.port(), other);
  EXPECT_TRUE(is_problem(other_refused, 507, "insufficient-storage")) << other_refused.body;

  const HttpReply ready = http_request(server.port(), "GET", "/readyz");
  EXPECT_EQ(ready.status, 503);
  EXPECT_THAT(ready.json()["checks"]["store"].get<std::string>(), HasSubstr("failing"));

  disk_->release();
  // /readyz tries a write again at most every 2 s (probes come often and the trial holds the store's write lock).
  const auto store_check = [&] { return http_request(server.port(), "GET", "/readyz").json()["checks"]["store"]; };
  nlohmann::json store = store_check();
  for (const auto deadline = Clock::now() + std::chrono::seconds(10); store != "ok" && Clock::now() < deadline;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    store = store_check();
  }
  EXPECT_EQ(store, "ok");
  const HttpReply accepted = submit_job(server.port(), image_job());
  EXPECT_EQ(accepted.status, 202) << accepted.body;
  EXPECT_EQ(http_request(server.port(), "GET", "/v1/jobs").json()["jobs"].size(), 2u);  // the 507s created nothing
}

// Starts a slow job, fills the disk while it runs and waits until the server says it cannot record the job's end.
std::string job_stuck_on_a_full_disk(ServerProcess& server, SmallFilesystem& disk) {
  const HttpReply accepted = submit_job(server.port(), slow_image_job(300));
  EXPECT_EQ(accepted.status, 202) << accepted.body;
  std::string id = accepted.json()["id"];
  wait_for_state(server.port(), id, "running", 30);
  disk.fill();
  EXPECT_TRUE(wait_for_log(server, "the store is full", 60)) << server.log();
  EXPECT_EQ(job_status(server.port(), id)["state"], "running");
  return id;
}

TEST_F(DiskFull, AJobWhoseEndCannotBeRecordedIsCancelableAndEndsOnceSpaceReturns) {
  ServerProcess server(data(), {"--threads-per-job", "1"});
  const std::string id = job_stuck_on_a_full_disk(server, *disk_);
  const HttpReply cancel = http_request(server.port(), "DELETE", "/v1/jobs/" + id);
  EXPECT_EQ(cancel.status, 202) << cancel.body;
  EXPECT_EQ(cancel.json()["cancel_requested"], true) << cancel.body;
  disk_->release();
  const nlohmann::json s = wait_for_job(server.port(), id, 30);
  EXPECT_EQ(s["state"], "canceled") << s.dump();
}

TEST_F(DiskFull, ResultsThatCannotBeWrittenFailTheJobWithAStorageProblem) {
  ServerProcess server(data(), {"--threads-per-job", "1"});
  const std::string id = job_stuck_on_a_full_disk(server, *disk_);
  disk_->release();
  const nlohmann::json s = wait_for_job(server.port(), id, 30);
  EXPECT_EQ(s["state"], "failed") << s.dump();
  EXPECT_EQ(s["error"]["type"], "urn:texwarp:problem:insufficient-storage") << s.dump();
  EXPECT_THAT(server.log(), Not(HasSubstr("job failed with an internal error")));
}

TEST_F(DiskFull, SigtermDoesNotWaitTheGraceAndTheJobRunsAgainAtTheNextStart) {
  std::string id;
  {
    ServerProcess server(data(), {"--threads-per-job", "1", "--shutdown-grace", "60"});
    id = job_stuck_on_a_full_disk(server, *disk_);
    const auto start = Clock::now();
    server.signal(SIGTERM);
    EXPECT_EQ(server.wait_exit(30), 0) << server.log();
    EXPECT_LT(seconds_since(start), 20.0);
  }
  disk_->release();
  ServerProcess restarted(data(), {"--threads-per-job", "1"});
  const nlohmann::json s = job_status(restarted.port(), id);
  EXPECT_THAT(s["state"].get<std::string>(), ::testing::AnyOf("queued", "running")) << s.dump();  // back in the queue
  EXPECT_THAT(restarted.log(), HasSubstr("\"requeued\":1"));
}

TEST(Orphans, TemporariesOfACrashedProcessAreRemovedAtStart) {
  const fs::path dir = test_folder();
  std::string id;
  {
    ServerProcess server(dir / "data");
    id = submit_job(server.port(), image_job()).json()["id"].get<std::string>();
    ASSERT_EQ(wait_for_job(server.port(), id)["state"], "succeeded");
    server.signal(SIGKILL);
    server.wait_exit(10);
  }
  fs::path blob_folder;
  for (const auto& entry : fs::directory_iterator(dir / "data" / "blobs")) blob_folder = entry.path();
  ASSERT_FALSE(blob_folder.empty());
  const std::vector<fs::path> orphans = {
      dir / "data" / "tmp" / "upload-99999-0", blob_folder / ".0123abcd.tmp-99999-0",
      dir / "data" / "results" / ".tmp-job_aaaaaaaaaaaaaaaaaaaaaaaaaa-1" / "warped.png",
      dir / "data" / "results" / "job_bbbbbbbbbbbbbbbbbbbbbbbbbb" / "warped.png",  // a job the store does not know
  };
  for (const auto& f : orphans) {
    fs::create_directories(f.parent_path());
    std::ofstream(f) << "left behind";
  }
  ServerProcess restarted(dir / "data");
  for (const auto& f : orphans) EXPECT_FALSE(fs::exists(f)) << f;
  EXPECT_FALSE(fs::exists(dir / "data" / "results" / "job_bbbbbbbbbbbbbbbbbbbbbbbbbb"));
  EXPECT_EQ(http_request(restarted.port(), "GET", "/v1/jobs/" + id + "/result").status, 200);  // kept
  EXPECT_EQ(http_request(restarted.port(), "GET", "/v1/jobs/" + id + "/files/warped.png").status, 200);
}

TEST(Draining, ReadyzSaysDrainingAndNewJobsGet503WhileAJobFinishes) {
  const fs::path dir = test_folder();
  ServerProcess server(dir / "data", {"--threads-per-job", "1", "--shutdown-grace", "60"});
  const std::string id = submit_job(server.port(), slow_image_job(500)).json()["id"];
  wait_for_state(server.port(), id, "running", 30);
  server.signal(SIGTERM);
  HttpReply ready;
  const auto deadline = Clock::now() + std::chrono::seconds(20);
  do {
    ready = http_request(server.port(), "GET", "/readyz");
  } while (ready.status == 200 && Clock::now() < deadline);
  EXPECT_EQ(ready.status, 503) << ready.body;
  EXPECT_EQ(ready.json()["status"], "draining") << ready.body;
  EXPECT_FALSE(ready.header("retry-after").empty());
  const HttpReply refused = submit_job(server.port(), image_job());
  EXPECT_TRUE(is_problem(refused, 503, "shutting-down")) << refused.body;
  EXPECT_FALSE(refused.header("retry-after").empty());
  EXPECT_EQ(job_status(server.port(), id)["state"], "running");  // status still answered
  EXPECT_EQ(http_request(server.port(), "DELETE", "/v1/jobs/" + id).status, 202);
  EXPECT_EQ(server.wait_exit(30), 0) << server.log();
  ServerProcess restarted(dir / "data");
  EXPECT_EQ(job_status(restarted.port(), id)["state"], "canceled");
}

// A second SIGTERM during the grace (an impatient operator, a supervisor's second try) stops running jobs at once;
// they go back to the queue, not counted as a crash, and run at the next start.
TEST(Draining, ASecondSignalEndsTheGraceAndRequeuesRunningJobs) {
  const fs::path dir = test_folder();
  ServerProcess server(dir / "data", {"--threads-per-job", "1", "--shutdown-grace", "600"});
  const std::string id = submit_job(server.port(), slow_image_job(500)).json()["id"];
  wait_for_state(server.port(), id, "running", 30);
  server.signal(SIGTERM);
  ASSERT_TRUE(wait_for_log(server, "shutting down", 10)) << server.log();
  const auto second = Clock::now();
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_exit(30), 0) << server.log();
  EXPECT_LT(seconds_since(second), 20.0);  // not the 600 s grace
  EXPECT_THAT(server.log(), HasSubstr("job interrupted by shutdown"));
  ServerProcess restarted(dir / "data", {"--threads-per-job", "1"});
  const nlohmann::json s = wait_for_job(restarted.port(), id);
  EXPECT_EQ(s["state"], "succeeded") << s.dump();
}

// How many OpenCL start-ups the start-up test makes: 5 by default, TEXWARP_OPENCL_STARTS (e.g. 20) for a soak run.
int opencl_starts() {
  const char* n = std::getenv("TEXWARP_OPENCL_STARTS");
  return n != nullptr && std::atoi(n) > 0 ? std::atoi(n) : 5;
}

// Starts texwarpd with four OpenCL workers and checks that it is ready with the device ok.
void expect_ready_opencl_start(const fs::path& data, std::vector<std::string> args, double* seconds) {
  const auto start = Clock::now();
  args.insert(args.end(), {"--device", "opencl"});
  ServerProcess server(data, args);
  const HttpReply ready = http_request(server.port(), "GET", "/readyz");
  *seconds = seconds_since(start);
  EXPECT_EQ(ready.json()["checks"]["device"]["status"], "ok") << ready.body << server.log();
  EXPECT_EQ(ready.json()["checks"]["store"], "ok") << ready.body;
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_exit(30), 0) << server.log();
  EXPECT_THAT(server.log(), Not(HasSubstr("no OpenCL platform")));
  EXPECT_THAT(server.log(), Not(HasSubstr("unavailable")));
}

TEST(OpenClStartup, FourWorkersStartCleanlyEveryTime) {
  const fs::path dir = test_folder();
  const int starts = opencl_starts();
  double total = 0.0;
  double slowest = 0.0;
  for (int i = 0; i < starts; ++i) {
    double seconds = 0.0;
    expect_ready_opencl_start(dir / ("data" + std::to_string(i)), {"--workers", "4"}, &seconds);
    total += seconds;
    slowest = std::max(slowest, seconds);
    if (HasFailure()) break;
  }
  std::cout << "[ figures  ] " << starts << " starts with --workers 4 --device opencl: mean " << total / starts
            << " s, slowest " << slowest << " s\n";
}

TEST(OpenClStartup, TheConfigFilesWorkersSettingStartsCleanly) {
  const fs::path dir = test_folder();
  std::ofstream(dir / "texwarpd.toml") << "workers = 4\n";
  double seconds = 0.0;
  expect_ready_opencl_start(dir / "data", {"--config", (dir / "texwarpd.toml").string()}, &seconds);
}

TEST(OpenClStartup, AColdKernelBuildKeepsTheServerAnsweringAndTheCompilerOutOfTheLog) {
  // A fresh PoCL cache: the server builds every kernel variant before /readyz says ready (tens of seconds on a
  // loaded machine). Meanwhile it answers: alive, not ready (its device "starting"), and a job submitted then
  // queues and runs once the kernels are built. The compiler's warnings must not reach stderr.
  const fs::path dir = test_folder();
  fs::create_directories(dir / "pocl-cache");
  ServerProcess server(dir / "data", {"--device", "opencl", "--workers", "2"},
                       {"POCL_CACHE_DIR=" + (dir / "pocl-cache").string()}, true, AwaitStart::kListening);
  EXPECT_EQ(http_request(server.port(), "GET", "/livez").status, 200);
  const HttpReply starting = http_request(server.port(), "GET", "/readyz");
  EXPECT_EQ(starting.status, 503) << starting.body;
  EXPECT_EQ(starting.json()["checks"]["device"]["status"], "starting") << starting.body;
  const HttpReply accepted = submit_job(server.port(), image_job());
  ASSERT_EQ(accepted.status, 202) << accepted.body;
  EXPECT_EQ(wait_for_job(server.port(), accepted.json()["id"], 180)["state"], "succeeded");
  EXPECT_EQ(http_request(server.port(), "GET", "/readyz").status, 200);
  const std::string log = server.log();
  EXPECT_THAT(log, Not(HasSubstr("warning")));
  EXPECT_THAT(log, Not(HasSubstr("generated")));
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    EXPECT_EQ(line.rfind('{', 0), 0u) << "not a JSON log line: " << line;
  }
}

}  // namespace
}  // namespace texwarp::testing
