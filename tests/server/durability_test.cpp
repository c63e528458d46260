// Durability of the real texwarpd across crashes and shutdowns: kill -9 with jobs queued and running (every job
// ends succeeded after a restart, none lost, nothing half-written served), half-published results left by a crash,
// a job that keeps crashing the server, and SIGTERM (running jobs re-queued, new submissions refused with 503).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <set>
#include <thread>

#include "api_helpers.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/server/sha256.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// Every result file of a succeeded job is whole: its bytes hash to what the manifest says.
void expect_whole_results(unsigned short port, const std::string& id) {
  const nlohmann::json r = http_request(port, "GET", "/v1/jobs/" + id + "/result").json();
  ASSERT_TRUE(r.contains("files")) << r.dump();
  for (const auto& f : r["files"]) {
    const HttpReply file = http_request(port, "GET", f["href"]);
    EXPECT_EQ(file.status, 200);
    EXPECT_EQ(server::sha256_hex(file.body), f["sha256"]) << id << " " << f["name"];
  }
}

int temp_result_folders(const fs::path& data) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(data / "results"))
    n += e.path().filename().string().rfind(".tmp-", 0) == 0;
  return n;
}

TEST(Durability, KillDashNineWithJobsInFlightLosesNothing) {
  const fs::path dir = test_folder();
  std::vector<std::string> ids;
  std::string slow;
  {
    ServerProcess server(dir / "data", {"--threads-per-job", "1"});
    slow = submit_job(server.port(), slow_image_job(400)).json()["id"];
    ids.push_back(slow);
    for (int i = 0; i < 5; ++i) {
      const HttpReply r = submit_job(server.port(), image_job());
      ASSERT_EQ(r.status, 202);
      ids.push_back(r.json()["id"]);
    }
    wait_for_state(server.port(), slow, "running", 30, 10);
    server.signal(SIGKILL);
    EXPECT_EQ(server.wait_exit(10), 128 + SIGKILL);
    EXPECT_EQ(temp_result_folders(dir / "data"), 1);  // the slow job's half-written results
  }
  ServerProcess restarted(dir / "data");
  EXPECT_FALSE(fs::exists(dir / "data" / "results" / (".tmp-" + slow + "-1")));  // the first attempt's, removed
  for (const auto& id : ids) {
    const nlohmann::json s = wait_for_job(restarted.port(), id);
    EXPECT_EQ(s["state"], "succeeded") << s.dump();
    expect_whole_results(restarted.port(), id);
  }
  EXPECT_EQ(job_status(restarted.port(), slow)["attempts"], 2);  // ran again from the start
  EXPECT_EQ(http_request(restarted.port(), "GET", "/v1/jobs").json()["jobs"].size(), ids.size());
  EXPECT_THAT(restarted.log(), HasSubstr("\"requeued\":1"));
  fs::remove_all(dir);
}

TEST(Durability, ResultsPublishedButNotRecordedAreRedone) {
  // A crash between renaming a job's result folder into place and recording it as succeeded leaves a complete-looking
  // folder for a job the store says is running: it must be produced again, never served as it is.
  const fs::path dir = test_folder();
  std::string id;
  {
    ServerProcess server(dir / "data", {"--threads-per-job", "1"});
    id = submit_job(server.port(), slow_image_job(400)).json()["id"];
    wait_for_state(server.port(), id, "running", 30, 5);
    server.signal(SIGKILL);
    server.wait_exit(10);
  }
  // The first run's folder, renamed into place but never recorded.
  fs::create_directories(dir / "data" / "results" / (id + ".1"));
  std::ofstream(dir / "data" / "results" / (id + ".1") / "warped.png") << "not the real image";
  ServerProcess restarted(dir / "data");
  ASSERT_EQ(wait_for_job(restarted.port(), id)["state"], "succeeded");
  expect_whole_results(restarted.port(), id);
  const HttpReply png = http_request(restarted.port(), "GET", "/v1/jobs/" + id + "/files/warped.png");
  EXPECT_EQ(png.body.substr(1, 3), "PNG");
  fs::remove_all(dir);
}

TEST(Durability, AJobThatKeepsCrashingTheServerIsFailedNotRetriedForever) {
  const fs::path dir = test_folder();
  std::string id;
  for (int crash = 0; crash < 2; ++crash) {
    ServerProcess server(dir / "data", {"--threads-per-job", "1", "--max-attempts", "2"});
    if (crash == 0) id = submit_job(server.port(), slow_image_job(400)).json()["id"];
    wait_for_state(server.port(), id, "running", 30, 2);
    server.signal(SIGKILL);
    server.wait_exit(10);
  }
  ServerProcess last(dir / "data", {"--max-attempts", "2"});
  const nlohmann::json s = job_status(last.port(), id);
  EXPECT_EQ(s["state"], "failed");
  EXPECT_EQ(s["attempts"], 2);
  EXPECT_EQ(s["error"]["type"], "urn:texwarp:problem:attempts-exhausted");
  fs::remove_all(dir);
}

TEST(Durability, SigtermRequeuesRunningJobsAndRefusesNewOnes) {
  const fs::path dir = test_folder();
  std::string id;
  {
    ServerProcess server(dir / "data", {"--threads-per-job", "1", "--shutdown-grace", "0.3"});
    id = submit_job(server.port(), slow_image_job(400)).json()["id"];
    wait_for_state(server.port(), id, "running", 30, 2);
    RawConnection open(server.port());  // a keep-alive client already connected
    const std::string body = image_job().dump();
    open.send("GET /livez HTTP/1.1\r\nHost: x\r\n\r\n");
    ASSERT_EQ(open.read_reply().status, 200);
    server.signal(SIGTERM);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    open.send("POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: " +
              std::to_string(body.size()) + "\r\n\r\n" + body);
    const HttpReply refused = open.read_reply();
    EXPECT_TRUE(is_problem(refused, 503, "shutting-down"));
    EXPECT_EQ(refused.header("retry-after"), "5");
    EXPECT_EQ(server.wait_exit(20), 0);  // a clean exit
    EXPECT_THAT(server.log(), HasSubstr("job interrupted by shutdown"));
  }
  ServerProcess restarted(dir / "data");
  const nlohmann::json s = wait_for_job(restarted.port(), id);
  EXPECT_EQ(s["state"], "succeeded");
  EXPECT_EQ(s["attempts"], 1);  // a shutdown is not a crash: the attempt was given back
  EXPECT_EQ(http_request(restarted.port(), "GET", "/v1/jobs").json()["jobs"].size(), 1u);  // the 503 created nothing
  fs::remove_all(dir);
}

TEST(Durability, SigtermLetsARunningJobFinishWithinTheGrace) {
  const fs::path dir = test_folder();
  ServerProcess server(dir / "data", {"--threads-per-job", "1", "--shutdown-grace", "60"});
  const std::string id = submit_job(server.port(), slow_image_job(250)).json()["id"];
  wait_for_state(server.port(), id, "running", 30);
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_exit(60), 0);
  ServerProcess restarted(dir / "data");
  const nlohmann::json s = job_status(restarted.port(), id);
  EXPECT_EQ(s["state"], "succeeded");  // finished before the old process exited
  EXPECT_EQ(s["attempts"], 1);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace texwarp::testing
