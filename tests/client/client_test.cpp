// libtexwarp_client against the real texwarpd: an image job and a mesh job submitted, waited for with progress
// and fetched (files checked); cancel; every error as a value with the server's problem; retries that honour
// Retry-After (against a scripted peer, to time them exactly); wait timeouts; atomic downloads.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <mutex>
#include <thread>

#include "client_test_support.hpp"
#include "scripted_peer.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/client/client.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using client::Client;
using client::ClientOptions;
using client::ErrorCode;
using ::testing::HasSubstr;

proto::JobSpec spec_of(const nlohmann::json& job) { return proto::decode_job_spec(job); }

class ClientE2E : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test_folder(); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ClientE2E, ImageJobSubmitWaitFetch) {
  ServerProcess server(dir_ / "data");
  Client c = client_for(server);
  // The texture goes up as a blob, the job refers to it.
  const std::string png = test_png(64);
  const auto blob = c.upload(png);
  ASSERT_TRUE(blob.ok()) << blob.error().message;
  EXPECT_TRUE(blob->created);
  proto::JobSpec job = spec_of(image_job());
  job.image.kind = proto::ImageSourceSpec::Kind::kBlob;
  job.image.blob = blob->id;

  const auto submitted = c.submit(job);
  ASSERT_TRUE(submitted.ok()) << submitted.error().message;
  // A worker may pick the job up before the 202 is written: any state but failed or canceled is right here.
  EXPECT_TRUE(submitted->state == proto::JobState::kQueued || submitted->state == proto::JobState::kRunning ||
              submitted->state == proto::JobState::kSucceeded);
  std::vector<int> progress;
  client::WaitOptions wait;
  wait.on_progress = [&](const proto::JobStatus& s) { progress.push_back(s.progress); };
  const auto done = c.wait(submitted->id, wait);
  ASSERT_TRUE(done.ok()) << done.error().message;
  EXPECT_EQ(done->state, proto::JobState::kSucceeded);
  ASSERT_FALSE(progress.empty());
  EXPECT_EQ(progress.back(), 100);
  EXPECT_TRUE(std::is_sorted(progress.begin(), progress.end()));

  const auto fetched = c.fetch_results(submitted->id, (dir_ / "out").string());
  ASSERT_TRUE(fetched.ok()) << fetched.error().message;
  ASSERT_EQ(fetched->paths.size(), 2u);
  EXPECT_EQ(fetched->paths[0], (dir_ / "out" / "warped.png").string());
  const Image warped = read_image(fetched->paths[0]);
  EXPECT_EQ(warped.width, 64);
  EXPECT_EQ(warped.height, 64);
  std::ifstream report_file(dir_ / "out" / "report.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  EXPECT_EQ(report, nlohmann::json::parse(fetched->result.report_json));
  EXPECT_LT(report["residuals"]["max_px"].get<double>(), 1e-6);
  // No temporary download files are left behind.
  for (const auto& e : fs::directory_iterator(dir_ / "out")) EXPECT_EQ(e.path().filename().string()[0] != '.', true);

  const auto bytes = c.fetch_file(submitted->id, "report.json");
  ASSERT_TRUE(bytes.ok());
  EXPECT_EQ(nlohmann::json::parse(bytes.value()), report);

  // The same report, typed.
  const auto typed = c.report(submitted->id);
  ASSERT_TRUE(typed.ok()) << typed.error().message;
  EXPECT_EQ(proto::encode_job_report(typed.value()), report);
  ASSERT_TRUE(typed->image);
  EXPECT_EQ(typed->image->residuals.max_px, report["residuals"]["max_px"].get<double>());
}

TEST_F(ClientE2E, MeshJobThroughRun) {
  ServerProcess server(dir_ / "data");
  Client c = client_for(server);
  const auto fetched = c.run(spec_of(mesh_job()), (dir_ / "mesh").string());
  ASSERT_TRUE(fetched.ok()) << fetched.error().message;
  EXPECT_EQ(fetched->result.kind, proto::JobKind::kMesh);
  EXPECT_TRUE(fs::exists(dir_ / "mesh" / "mesh.obj"));
  EXPECT_TRUE(fs::exists(dir_ / "mesh" / "uvs.json"));
  EXPECT_TRUE(fs::exists(dir_ / "mesh" / "warped.png"));
  EXPECT_EQ(nlohmann::json::parse(fetched->result.report_json)["flipped_triangles"], 0);
  const auto typed = c.report(fetched->result.job_id);
  ASSERT_TRUE(typed.ok()) << typed.error().message;
  ASSERT_TRUE(typed->mesh);
  EXPECT_EQ(typed->mesh->uvs.flipped_triangles, 0);
  EXPECT_EQ(typed->files, (std::vector<std::string>{"mesh.obj", "uvs.json", "warped.png", "report.json"}));
}

// Version skew: a report from a texwarpd one version older lacks the keys added since (here a real report of this
// server with them removed, served over HTTP as that server's /result): the client reads it, those members unknown.
TEST_F(ClientE2E, AReportFromAnOlderServerWithoutLaterKeysIsReadWithThemUnknown) {
  ServerProcess server(dir_ / "data");
  Client c = client_for(server);
  const auto done = c.run(spec_of(mesh_job()), (dir_ / "mesh").string());
  ASSERT_TRUE(done.ok()) << done.error().message;
  const std::string id = done->result.job_id;
  const auto current = c.report(id);
  ASSERT_TRUE(current.ok()) << current.error().message;
  ASSERT_TRUE(current->mesh && current->mesh->mesh.triangles && current->mesh->region.triangles);
  ASSERT_TRUE(current->mesh->embedding && current->mesh->flips);

  proto::JobResult older = done->result;
  nlohmann::json report = nlohmann::json::parse(older.report_json);
  for (const char* key : {"embedding", "flips"}) ASSERT_EQ(report.erase(key), 1u) << key;
  ASSERT_EQ(report["mesh"].erase("triangles"), 1u);
  ASSERT_EQ(report["region"].erase("triangles"), 1u);
  older.report_json = report.dump();
  const std::string body = proto::encode_job_result(older).dump();
  ScriptedPeer peer({scripted_reply(200, "Content-Type: application/json\r\n", body)});
  ClientOptions options;
  options.server = peer.url();
  options.max_retries = 0;
  const auto read = Client(options).report(id);
  ASSERT_TRUE(read.ok()) << read.error().message;
  EXPECT_EQ(peer.request_lines(), (std::vector<std::string>{"GET /v1/jobs/" + id + "/result HTTP/1.1"}));
  ASSERT_TRUE(read->mesh);
  EXPECT_FALSE(read->mesh->mesh.triangles.has_value());
  EXPECT_FALSE(read->mesh->region.triangles.has_value());
  EXPECT_FALSE(read->mesh->embedding.has_value());
  EXPECT_FALSE(read->mesh->flips.has_value());
  // Everything else as the server said.
  proto::JobReport expected = current.value();
  expected.mesh->mesh.triangles.reset();
  expected.mesh->region.triangles.reset();
  expected.mesh->embedding.reset();
  expected.mesh->flips.reset();
  EXPECT_EQ(read.value(), expected);

  // A key of the first version missing is still a protocol error naming it.
  report["mesh"].erase("faces");
  older.report_json = report.dump();
  ScriptedPeer broken(
      {scripted_reply(200, "Content-Type: application/json\r\n", proto::encode_job_result(older).dump())});
  options.server = broken.url();
  const auto refused = Client(options).report(id);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kProtocol);
  EXPECT_THAT(refused.error().message, HasSubstr("mesh.faces"));
}

TEST_F(ClientE2E, CancelAndWaitTimeout) {
  ServerProcess server(dir_ / "data", {"--threads-per-job", "1"});
  Client c = client_for(server);
  const auto submitted = c.submit(spec_of(slow_image_job(600)));
  ASSERT_TRUE(submitted.ok());
  client::WaitOptions brief;
  brief.timeout = std::chrono::milliseconds(200);
  const auto timed_out = c.wait(submitted->id, brief);
  ASSERT_FALSE(timed_out.ok());
  EXPECT_EQ(timed_out.error().code, ErrorCode::kTimeout);
  const auto canceled = c.cancel(submitted->id);
  ASSERT_TRUE(canceled.ok()) << canceled.error().message;
  EXPECT_TRUE(canceled->cancel_requested);
  const auto done = c.wait(submitted->id);
  ASSERT_TRUE(done.ok());
  EXPECT_EQ(done->state, proto::JobState::kCanceled);
  const auto again = c.cancel(submitted->id);  // finished: 409 job-finished, nothing changed
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.error().code, ErrorCode::kWrongState);
  EXPECT_EQ(c.status(submitted->id)->state, proto::JobState::kCanceled);
  const auto result = c.result(submitted->id);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().http_status, 409);
  // run() says how a job ended when it does not succeed.
  const auto failed = c.run(
      [] {
        nlohmann::json j = mesh_job();
        j["mesh"]["region"] = {{"faces", {0, 71}}};
        return spec_of(j);
      }(),
      (dir_ / "never").string());
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().code, ErrorCode::kJobFailed);
  ASSERT_TRUE(failed.error().problem);
  EXPECT_EQ(failed.error().problem->path, "$.mesh.region");
  EXPECT_FALSE(fs::exists(dir_ / "never" / "mesh.obj"));
}

TEST_F(ClientE2E, ErrorsAreValuesWithTheServersProblem) {
  ServerProcess server(dir_ / "data");
  Client c = client_for(server);
  nlohmann::json bad = image_job();
  bad["warp"]["features"][2]["target"] = {1, 2, 3};
  const auto refused = c.submit_json(bad.dump());
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kHttp);
  EXPECT_EQ(refused.error().http_status, 422);
  ASSERT_TRUE(refused.error().problem);
  EXPECT_EQ(refused.error().problem->path, "$.warp.features[2].target");
  EXPECT_THAT(refused.error().message, HasSubstr("expected a point"));

  const auto unknown = c.status("job_aaaaaaaaaaaaaaaaaaaaaaaaaa");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().http_status, 404);
  EXPECT_EQ(c.status("../etc").error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(c.upload_file((dir_ / "missing.png").string()).error().code, ErrorCode::kInvalidArgument);

  const auto ready = c.ready();
  ASSERT_TRUE(ready.ok());
  EXPECT_TRUE(nlohmann::json::parse(ready.value()).contains("checks"));

  ClientOptions https;
  https.server = "https://127.0.0.1:1";
  EXPECT_EQ(Client(https).status("job_x").error().code, ErrorCode::kInvalidArgument);
  ClientOptions nonsense;
  nonsense.server = "http://host:port/path";
  EXPECT_EQ(Client(nonsense).list().error().code, ErrorCode::kInvalidArgument);
}

TEST_F(ClientE2E, ConnectionRefusedAfterItsRetries) {
  ClientOptions options;
  options.server = "http://127.0.0.1:1";  // nothing listens on port 1 (privileged, unassigned here)
  options.max_retries = 2;
  options.initial_backoff = std::chrono::milliseconds(50);
  Client c(options);
  const auto start = std::chrono::steady_clock::now();
  const auto r = c.list();
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kConnection);
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(150));  // 50 + 100 ms of backoff
}

TEST_F(ClientE2E, BearerToken) {
  std::ofstream(dir_ / "token") << "tok-123";
  ServerProcess server(dir_ / "data", {"--token-file", (dir_ / "token").string()});
  ClientOptions options;
  options.server = server.url();
  EXPECT_EQ(Client(options).list().error().http_status, 401);
  options.token = "tok-123";
  EXPECT_TRUE(Client(options).list().ok());
}

TEST(ClientRetries, HonourRetryAfterOn429And503) {
  const std::string page = R"({"jobs": [], "next_cursor": null})";
  ScriptedPeer peer({scripted_reply(429, "Retry-After: 1\r\n", "{}"), scripted_reply(503, "Retry-After: 0\r\n", "{}"),
                     scripted_reply(200, "Content-Type: application/json\r\n", page)});
  ClientOptions options;
  options.server = "http://127.0.0.1:" + std::to_string(peer.port());
  options.initial_backoff = std::chrono::milliseconds(5);
  Client c(options);
  const auto r = c.list();
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_TRUE(r->jobs.empty());
  const auto arrivals = peer.arrivals();
  ASSERT_EQ(arrivals.size(), 3u);
  EXPECT_GE(arrivals[1] - arrivals[0], std::chrono::milliseconds(990));  // Retry-After: 1
  EXPECT_LT(arrivals[2] - arrivals[1], std::chrono::milliseconds(500));  // Retry-After: 0
}

TEST(ClientRetries, GiveUpAfterMaxRetriesWithTheLastAnswer) {
  const std::string problem = R"({"type": "urn:texwarp:problem:queue-full", "title": "Queue full", "status": 429,
                                  "detail": "the server has 4 jobs waiting"})";
  ScriptedPeer peer(
      {scripted_reply(429, "Retry-After: 0\r\n", problem), scripted_reply(429, "Retry-After: 0\r\n", problem)});
  ClientOptions options;
  options.server = "http://127.0.0.1:" + std::to_string(peer.port());
  options.max_retries = 1;
  Client c(options);
  const auto r = c.list();
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().http_status, 429);
  ASSERT_TRUE(r.error().problem);
  EXPECT_EQ(r.error().problem->type, "urn:texwarp:problem:queue-full");
  EXPECT_EQ(peer.arrivals().size(), 2u);
}

TEST(ClientRetries, ATimeoutIsAnError) {
  ScriptedPeer peer({kHold});
  ClientOptions options;
  options.server = "http://127.0.0.1:" + std::to_string(peer.port());
  options.request_timeout = std::chrono::milliseconds(300);
  options.max_retries = 0;
  Client c(options);
  const auto start = std::chrono::steady_clock::now();
  const auto r = c.status("job_x");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kTimeout) << r.error().message;
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(290));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(3));
}

}  // namespace
}  // namespace texwarp::testing
