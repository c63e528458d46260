// The farm commands of the real `texwarp` binary: submit/status/list/wait/fetch/cancel/purge/nodes against the real
// texwarpd, and `run` with no server; their documented exit codes (0 ok, 1 failure, 2 invalid input, 3 canceled,
// 4 timed out), progress lines, outputs that appear whole or not at all, waits that outlive a server restart
// (--retry-budget), and the farm queue's flags (--priority, --label, several job files as one batch).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <iostream>
#include <sstream>
#include <thread>

#include "server_process.hpp"
#include "test_jobs.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

struct CliRun {
  int code = -1;
  std::string out;
  std::string err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class CliFarm : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test_folder(); }
  void TearDown() override {
    server_.reset();
    fs::remove_all(dir_);
  }

  // `prefix` goes before the binary (e.g. "timeout ...").
  CliRun run(const std::string& args, const std::string& prefix = "") const {
    const fs::path out = dir_ / "stdout.txt";
    const fs::path err = dir_ / "stderr.txt";
    const std::string cmd = prefix + std::string(TEXWARP_CLI) + " " + args + " >" + out.string() + " 2>" + err.string();
    const int status = std::system(cmd.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
  }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return (dir_ / name).string();
  }
  std::string server_arg() const { return " --server " + server_->url(); }
  void start() {
    server_ = std::make_unique<ServerProcess>(dir_ / "data", std::vector<std::string>{"--threads-per-job", "1"});
  }

  fs::path dir_;
  std::unique_ptr<ServerProcess> server_;
};

TEST_F(CliFarm, SubmitStatusWaitFetch) {
  start();
  const std::string job = write("job.json", image_job().dump());
  const CliRun submitted = run("submit " + job + server_arg());
  ASSERT_EQ(submitted.code, 0) << submitted.err;
  const std::string id = nlohmann::json::parse(submitted.out)["id"];

  const CliRun waited = run("wait " + id + server_arg());
  EXPECT_EQ(waited.code, 0) << waited.err;
  EXPECT_THAT(waited.err, HasSubstr("texwarp: job " + id + " succeeded 100%"));
  EXPECT_EQ(nlohmann::json::parse(waited.out)["state"], "succeeded");

  const CliRun status = run("status " + id + server_arg());
  EXPECT_EQ(status.code, 0);
  EXPECT_EQ(nlohmann::json::parse(status.out)["progress"], 100);
  const CliRun listed = run("status --state succeeded" + server_arg());
  EXPECT_EQ(nlohmann::json::parse(listed.out)["jobs"][0]["id"], id);

  const CliRun fetched = run("fetch " + id + " --out " + (dir_ / "results").string() + server_arg());
  EXPECT_EQ(fetched.code, 0) << fetched.err;
  EXPECT_EQ(fetched.out,
            (dir_ / "results" / "warped.png").string() + "\n" + (dir_ / "results" / "report.json").string() + "\n");
  EXPECT_EQ(slurp(dir_ / "results" / "warped.png").substr(1, 3), "PNG");
}

TEST_F(CliFarm, SubmitUploadsLocalFilesWaitsAndDownloads) {
  start();
  write("texture.png", test_png(64));
  nlohmann::json job = image_job();
  // Relative to the job file, on this machine; what the image holds travels with it when it is uploaded.
  job["image"] = {{"path", "texture.png"}, {"role", "data"}, {"normal_convention", "directx"}};
  const std::string file = write("local-job.json", job.dump());
  const CliRun r = run("submit " + file + " --upload --out " + (dir_ / "out").string() + server_arg());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("texwarp: wrote " + (dir_ / "out" / "report.json").string()));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "warped.png"));
  const nlohmann::json report = nlohmann::json::parse(slurp(dir_ / "out" / "report.json"));
  EXPECT_EQ(report["output"]["sampling"]["role"], "data") << report.dump();
}

TEST_F(CliFarm, SubmitUploadsTheTilesOfAUdimPath) {
  // texwarpd reads nothing from this machine: --upload sends tiles 1001 and 1002 one by one; the warped tiles are
  // those `texwarp run` writes from the same <UDIM> path here.
  start();
  write("texture.1001.png", test_png(64));
  write("texture.1002.png", test_png(64));
  nlohmann::json job = image_job();
  job["image"] = {{"path", "texture.<UDIM>.png"}};
  const std::string file = write("udim-job.json", job.dump());
  const CliRun r = run("submit " + file + " --upload --out " + (dir_ / "out").string() + server_arg());
  ASSERT_EQ(r.code, 0) << r.err;
  const CliRun local = run("run " + file + " --out " + (dir_ / "local").string() + " --quiet");
  ASSERT_EQ(local.code, 0) << local.err;
  for (const char* tile : {"warped.1001.png", "warped.1002.png"}) {
    ASSERT_TRUE(fs::exists(dir_ / "out" / tile)) << tile;
    EXPECT_EQ(slurp(dir_ / "out" / tile), slurp(dir_ / "local" / tile)) << tile;
  }
  // A token that matches no file here is refused before anything is sent.
  job["image"] = {{"path", "none.<UDIM>.png"}};
  const std::string none = write("none-job.json", job.dump());
  const CliRun refused = run("submit " + none + " --upload" + server_arg());
  EXPECT_EQ(refused.code, 2) << refused.err;
  EXPECT_THAT(refused.err, HasSubstr("\"none.<UDIM>.png\" matches no UDIM tile"));
}

TEST_F(CliFarm, CancelTimeoutAndFailureExitCodes) {
  start();
  const std::string slow = write("slow.json", slow_image_job(600).dump());
  const std::string id = nlohmann::json::parse(run("submit " + slow + server_arg()).out)["id"];
  const CliRun timed_out = run("wait " + id + " --timeout 0.3 --quiet" + server_arg());
  EXPECT_EQ(timed_out.code, 4) << timed_out.err;
  EXPECT_THAT(timed_out.err, HasSubstr("after the wait timeout"));
  const CliRun canceled = run("cancel " + id + server_arg());
  EXPECT_EQ(canceled.code, 0) << canceled.err;
  EXPECT_EQ(run("wait " + id + " --quiet" + server_arg()).code, 3);
  EXPECT_EQ(run("cancel " + id + server_arg()).code, 2);  // 409: already finished

  nlohmann::json bad = image_job();
  bad["warp"]["features"][0]["source"] = "here";
  const CliRun refused = run("submit " + write("bad.json", bad.dump()) + server_arg());
  EXPECT_EQ(refused.code, 2);
  EXPECT_THAT(refused.err, HasSubstr("$.warp.features[0].source"));

  nlohmann::json not_a_disk = mesh_job();
  not_a_disk["mesh"]["region"] = {{"faces", {0, 71}}};
  const CliRun failed = run("submit " + write("fails.json", not_a_disk.dump()) + " --wait --quiet" + server_arg());
  EXPECT_EQ(failed.code, 1);
  EXPECT_THAT(failed.err, HasSubstr("not a single disk"));
  EXPECT_THAT(failed.err, HasSubstr("$.mesh.region"));

  EXPECT_EQ(run("status job_aaaaaaaaaaaaaaaaaaaaaaaaaa" + server_arg()).code, 2);  // 404
  const CliRun unreachable = run("status --retry-budget 0 --server http://127.0.0.1:1");
  EXPECT_EQ(unreachable.code, 1);
  EXPECT_THAT(unreachable.err, HasSubstr("cannot connect"));
}

// `texwarp wait` started while the job runs; texwarpd gets SIGTERM (no grace: the job goes back to the queue) and
// a new one starts 5 s later on the same port and data folder: the wait goes on and exits 0 with the job done.
TEST_F(CliFarm, WaitOutlivesAServerRestart) {
  const std::vector<std::string> args = {"--threads-per-job", "1", "--workers", "1", "--shutdown-grace", "0"};
  server_ = std::make_unique<ServerProcess>(dir_ / "data", args);
  const unsigned short port = server_->port();
  const std::string slow = write("slow.json", slow_image_job(300).dump());
  const CliRun submitted = run("submit " + slow + server_arg());
  ASSERT_EQ(submitted.code, 0) << submitted.err;
  const std::string id = nlohmann::json::parse(submitted.out)["id"];

  const auto start = std::chrono::steady_clock::now();
  CliRun waited;
  // Its arguments made here: the thread must not read server_, which is replaced below (a race TSan found).
  const std::string wait_args = "wait " + id + server_arg();
  std::thread waiter([&] { waited = run(wait_args); });
  // The wait has seen the job running (its progress line) before the server goes.
  const std::string running_line = "texwarp: job " + id + " running";
  bool seen = false;
  while (!seen && std::chrono::steady_clock::now() - start < std::chrono::seconds(60)) {
    seen = slurp(dir_ / "stderr.txt").find(running_line) != std::string::npos;
    if (!seen) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!seen) {
    server_->signal(SIGKILL);
    waiter.join();
    FAIL() << "the wait never showed the job running: " << waited.err;
  }
  const auto stop = std::chrono::steady_clock::now();
  server_->signal(SIGTERM);
  EXPECT_EQ(server_->wait_exit(30), 0) << server_->log();
  EXPECT_THAT(server_->log(), HasSubstr("job interrupted by shutdown"));  // it did not finish before the restart
  std::this_thread::sleep_until(stop + std::chrono::seconds(5));          // the outage: nobody listens on the port
  server_ = std::make_unique<ServerProcess>(ListenPort{port}, dir_ / "data", args);
  waiter.join();
  std::cout << "[ measure  ] texwarp wait across the restart took "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() << " s\n";

  EXPECT_EQ(waited.code, 0) << waited.err;
  EXPECT_THAT(waited.err, HasSubstr("texwarp: job " + id + " succeeded 100%"));
  ASSERT_FALSE(waited.out.empty()) << waited.err;
  const nlohmann::json final_status = nlohmann::json::parse(waited.out);
  EXPECT_EQ(final_status["state"], "succeeded");
}

TEST_F(CliFarm, RetryBudgetFromTheFlagOrTheEnvironment) {
  // Bound but never listening: connections to it are refused.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  socklen_t len = sizeof addr;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  const std::string dead = " --server http://127.0.0.1:" + std::to_string(ntohs(addr.sin_port));

  auto start = std::chrono::steady_clock::now();
  const CliRun flag = run("wait job_aaaaaaaaaaaaaaaaaaaaaaaaaa --retry-budget 1.5" + dead);
  double spent_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(flag.code, 1) << flag.err;
  EXPECT_THAT(flag.err, HasSubstr("cannot connect"));
  EXPECT_GE(spent_s, 1.5);
  EXPECT_LT(spent_s, 6.0);

  start = std::chrono::steady_clock::now();
  const CliRun env = run("status job_aaaaaaaaaaaaaaaaaaaaaaaaaa" + dead, "TEXWARP_RETRY_BUDGET=1 ");
  spent_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(env.code, 1) << env.err;
  EXPECT_GE(spent_s, 1.0);
  EXPECT_LT(spent_s, 6.0);

  // The flag wins over the environment.
  start = std::chrono::steady_clock::now();
  EXPECT_EQ(run("status" + dead + " --retry-budget 0", "TEXWARP_RETRY_BUDGET=30 ").code, 1);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(3));

  const CliRun bad_env = run("status" + dead, "TEXWARP_RETRY_BUDGET=soon ");
  EXPECT_EQ(bad_env.code, 2);
  EXPECT_THAT(bad_env.err, HasSubstr("TEXWARP_RETRY_BUDGET"));
  EXPECT_THAT(bad_env.err, HasSubstr("\"soon\""));
  const CliRun bad_flag = run("submit " + write("job.json", image_job().dump()) + " --retry-budget=-1" + dead);
  EXPECT_EQ(bad_flag.code, 2);
  EXPECT_THAT(bad_flag.err, HasSubstr("--retry-budget"));
  ::close(fd);
}

TEST_F(CliFarm, TheClientExampleProgramRunsTheShippedJob) {
  start();
  const std::string job = (fs::path(TEXWARP_SOURCE_DIR) / "examples" / "astronaut-job.json").string();
  const std::string cmd = std::string(TEXWARP_CLIENT_EXAMPLE) + " " + job + " " + (dir_ / "example").string() + " " +
                          server_->url() + " >" + (dir_ / "example.txt").string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 0) << slurp(dir_ / "example.txt");
  EXPECT_THAT(slurp(dir_ / "example.txt"), HasSubstr("succeeded 100%"));
  EXPECT_TRUE(fs::exists(dir_ / "example" / "warped.png"));
  EXPECT_TRUE(fs::exists(dir_ / "example" / "report.json"));
}

TEST_F(CliFarm, SubmitWithPriorityAndLabelsThenListByLabel) {
  start();
  const std::string job = write("job.json", image_job().dump());
  const CliRun submitted =
      run("submit " + job + " --priority 12 --label team=fx --label 'shot=sq 1&2=3 ü'" + server_arg());
  ASSERT_EQ(submitted.code, 0) << submitted.err;
  const nlohmann::json status = nlohmann::json::parse(submitted.out);
  EXPECT_EQ(status["priority"], 12);
  EXPECT_EQ(status["labels"], nlohmann::json({{"team", "fx"}, {"shot", "sq 1&2=3 ü"}}));
  const std::string id = status["id"];
  const CliRun plain = run("submit " + job + server_arg());  // the file's own priority and labels: none
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_EQ(nlohmann::json::parse(plain.out)["priority"], 0);

  const CliRun by_label = run("list --label 'shot=sq 1&2=3 ü' --label team=fx" + server_arg());
  ASSERT_EQ(by_label.code, 0) << by_label.err;
  const nlohmann::json page = nlohmann::json::parse(by_label.out);
  ASSERT_EQ(page["jobs"].size(), 1u);
  EXPECT_EQ(page["jobs"][0]["id"], id);
  EXPECT_EQ(nlohmann::json::parse(run("list --label team=other" + server_arg()).out)["jobs"].size(), 0u);
  EXPECT_EQ(nlohmann::json::parse(run("list" + server_arg()).out)["jobs"].size(), 2u);

  // Bad flags: exit 2, the flag named, nothing sent.
  const auto refused = [&](const std::string& args, const std::string& says) {
    const CliRun r = run(args + server_arg());
    EXPECT_EQ(r.code, 2) << args << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr(says)) << args;
  };
  refused("submit " + job + " --priority 1001", "--priority");
  refused("submit " + job + " --priority high", "--priority");
  refused("submit " + job + " --label team", "--label: expected KEY=VALUE, got \"team\"");
  refused("submit " + job + " --label 'bad key=v'", "--label: a label key \"bad key\" may hold only");
  refused("submit " + job + " --label a=1 --label a=2", "the key \"a\" is given twice");
  refused("submit " + job + " --label k=" + std::string(257, 'v'), "at most 256 bytes");
  refused("list --label =v", "--label: a label key cannot be empty");
  refused("list --state lost", "--state");
  EXPECT_EQ(nlohmann::json::parse(run("list" + server_arg()).out)["jobs"].size(), 2u);
}

TEST_F(CliFarm, SeveralJobFilesAreOneBatch) {
  start();
  std::vector<std::string> files;
  for (const std::string name : {"a", "b", "c"}) {
    nlohmann::json job = image_job();
    job["name"] = name;
    files.push_back(write(name + ".json", job.dump()));
  }
  const CliRun submitted =
      run("submit " + files[0] + " " + files[1] + " " + files[2] + " --label batch=1 --priority 3" + server_arg());
  ASSERT_EQ(submitted.code, 0) << submitted.err;
  const nlohmann::json batch = nlohmann::json::parse(submitted.out);
  ASSERT_EQ(batch["jobs"].size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(batch["jobs"][i]["name"], std::string(1, static_cast<char>('a' + i)));
    EXPECT_EQ(batch["jobs"][i]["labels"]["batch"], "1");
    EXPECT_EQ(batch["jobs"][i]["priority"], 3);
  }
  const std::string last_id = batch["jobs"][2]["id"];
  EXPECT_EQ(run("wait " + last_id + " --quiet" + server_arg()).code, 0);

  // One bad file: refused before anything is sent, the file and the path named.
  nlohmann::json bad = image_job();
  bad["warp"]["features"][0]["source"] = "here";
  const CliRun refused = run("submit " + files[0] + " " + write("bad.json", bad.dump()) + server_arg());
  EXPECT_EQ(refused.code, 2);
  EXPECT_THAT(refused.err, HasSubstr("bad.json: $.warp.features[0].source"));
  // One job the server refuses (a blob it does not hold): the file named, nothing stored.
  nlohmann::json missing = image_job();
  missing["image"] = {{"blob", "sha256:" + std::string(64, 'e')}};
  const CliRun server_refused = run("submit " + files[0] + " " + write("missing.json", missing.dump()) + server_arg());
  EXPECT_EQ(server_refused.code, 2) << server_refused.err;
  EXPECT_THAT(server_refused.err, HasSubstr("missing.json was refused; no job of the batch was submitted"));
  EXPECT_THAT(server_refused.err, HasSubstr("$.jobs[1].image"));
  EXPECT_EQ(nlohmann::json::parse(run("list" + server_arg()).out)["jobs"].size(), 3u);

  const CliRun with_wait = run("submit " + files[0] + " " + files[1] + " --wait" + server_arg());
  EXPECT_EQ(with_wait.code, 2);
  EXPECT_THAT(with_wait.err, HasSubstr("--wait: takes one job file"));
}

TEST_F(CliFarm, PurgeAFinishedJobAndListTheNodes) {
  start();
  const std::string job = write("job.json", image_job().dump());
  const std::string id = nlohmann::json::parse(run("submit " + job + server_arg()).out)["id"];
  ASSERT_EQ(run("wait " + id + " --quiet" + server_arg()).code, 0);
  const CliRun purged = run("purge " + id + server_arg());
  EXPECT_EQ(purged.code, 0) << purged.err;
  EXPECT_THAT(purged.err, HasSubstr("texwarp: purged job " + id));
  EXPECT_EQ(run("status " + id + server_arg()).code, 2);  // 404
  const CliRun again = run("purge " + id + server_arg());
  EXPECT_EQ(again.code, 2);
  EXPECT_THAT(again.err, HasSubstr("404"));

  const std::string slow = write("slow.json", slow_image_job(600).dump());
  const std::string slow_id = nlohmann::json::parse(run("submit " + slow + server_arg()).out)["id"];
  const CliRun unfinished = run("purge " + slow_id + server_arg());
  EXPECT_EQ(unfinished.code, 2);
  EXPECT_THAT(unfinished.err, HasSubstr("only a finished job can be purged"));
  EXPECT_EQ(run("cancel " + slow_id + " --wait" + server_arg()).code, 0);
  EXPECT_EQ(run("purge ../etc" + server_arg()).code, 2);

  const CliRun nodes = run("nodes" + server_arg());
  ASSERT_EQ(nodes.code, 0) << nodes.err;
  const nlohmann::json list = nlohmann::json::parse(nodes.out);
  ASSERT_EQ(list["nodes"].size(), 1u);
  EXPECT_EQ(list["nodes"][0]["alive"], true);
  EXPECT_EQ(list["nodes"][0]["pid"], server_->pid());
}

TEST_F(CliFarm, RunAJobHereWithoutAServer) {
  const std::string job = write("job.json", image_job(96).dump());
  const CliRun r = run("run " + job + " --out " + (dir_ / "out").string() + " --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("progress 100%"));
  EXPECT_EQ(r.out, (dir_ / "out" / "warped.png").string() + "\n" + (dir_ / "out" / "report.json").string() + "\n");
  const nlohmann::json report = nlohmann::json::parse(slurp(dir_ / "out" / "report.json"));
  EXPECT_EQ(report["output"]["width"], 96);
  EXPECT_EQ(report["backend"], "cpu");
  for (const auto& e : fs::directory_iterator(dir_ / "out")) EXPECT_NE(e.path().filename().string()[0], '.');

  // A mesh job with its mesh by path, relative to the job file.
  nlohmann::json mesh = mesh_job();
  write("grid.json", mesh["mesh"]["source"]["inline"].dump());
  mesh["mesh"]["source"] = {{"path", "grid.json"}};
  const CliRun m = run("run " + write("mesh-job.json", mesh.dump()) + " --out " + (dir_ / "mesh").string() +
                       " --backend cpu --quiet");
  EXPECT_EQ(m.code, 0) << m.err;
  EXPECT_TRUE(fs::exists(dir_ / "mesh" / "mesh.obj"));
  EXPECT_EQ(m.err.find("progress"), std::string::npos);
}

TEST_F(CliFarm, RunRefusesWhatItCannotRunAndLeavesNothing) {
  nlohmann::json job = image_job();
  job["warp"]["tolerance_px"] = -1;
  const CliRun invalid = run("run " + write("job.json", job.dump()) + " --out " + (dir_ / "out").string());
  EXPECT_EQ(invalid.code, 2);
  EXPECT_THAT(invalid.err, HasSubstr("job.json: $.warp.tolerance_px"));
  job = image_job();
  job["image"] = {{"blob", "sha256:" + std::string(64, 'e')}};
  const CliRun blob = run("run " + write("blob.json", job.dump()) + " --out " + (dir_ / "out").string());
  EXPECT_EQ(blob.code, 2);
  EXPECT_THAT(blob.err, HasSubstr("$.image.blob"));
  EXPECT_TRUE(fs::is_empty(dir_ / "out"));
}

TEST_F(CliFarm, RunInterruptedLeavesTheOutputFolderAsItWas) {
  const std::string slow = write("slow.json", slow_image_job(600).dump());
  // SIGINT once the run's work folder exists (its handler is installed by then), however slowly the process starts.
  const std::string out = (dir_ / "out").string();
  const std::string script = std::string(TEXWARP_CLI) + " run " + slow + " --out " + out +
                             " --backend cpu --threads 1 >" + (dir_ / "stdout.txt").string() + " 2>" +
                             (dir_ / "stderr.txt").string() + " & pid=$!; for i in $(seq 1 2400); do ls -A " + out +
                             " 2>/dev/null | grep -q texwarp-run && break; sleep 0.05; done; kill -INT $pid; wait $pid";
  const int status = std::system(("bash -c '" + script + "'").c_str());
  const CliRun r{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(dir_ / "stdout.txt"), slurp(dir_ / "stderr.txt")};
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("canceled"));
  EXPECT_TRUE(fs::is_empty(dir_ / "out"));
}

}  // namespace
}  // namespace texwarp::testing
