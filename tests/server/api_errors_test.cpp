// Every 4xx the API answers, through the real texwarpd: each is an RFC 9457 problem whose detail says what to fix
// and, for a job, whose `path` names the offending value; and a 500 shows nothing of the server's insides.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "api_helpers.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/base64.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

class ApiErrors : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test_folder("-suite"));
    fs::create_directories(*dir_ / "root");
    fs::create_directories(*dir_ / "elsewhere");
    std::ofstream(*dir_ / "elsewhere" / "t.png", std::ios::binary) << test_png(64);
    server_ = new ServerProcess(*dir_ / "data",
                                {"--max-features", "8", "--max-image-megapixels", "0.01", "--max-output-megapixels",
                                 "1", "--max-job-body-mb", "1", "--max-header-bytes", "2048", "--read-timeout", "1",
                                 "--input-root", (*dir_ / "root").string()});
  }
  static void TearDownTestSuite() {
    delete server_;
    fs::remove_all(*dir_);
    delete dir_;
  }
  static unsigned short port() { return server_->port(); }

  static ServerProcess* server_;
  static fs::path* dir_;
};

ServerProcess* ApiErrors::server_ = nullptr;
fs::path* ApiErrors::dir_ = nullptr;

std::string problem_path(const HttpReply& r) { return r.json().value("path", ""); }
std::string detail(const HttpReply& r) { return r.json().value("detail", ""); }

TEST_F(ApiErrors, MalformedJsonIs400) {
  const HttpReply r = http_request(port(), "POST", "/v1/jobs", "{\"image\": ");
  EXPECT_TRUE(is_problem(r, 400, "malformed-json"));
  EXPECT_THAT(detail(r), HasSubstr("not valid JSON"));
  EXPECT_EQ(r.json()["instance"], "/v1/jobs");
}

TEST_F(ApiErrors, MalformedHttpIs400) {
  EXPECT_TRUE(is_problem(raw_exchange(port(), "GET /v1/jobs HTTP/1.1\r\nHost x\r\n\r\n"), 400, "malformed-request"));
}

TEST_F(ApiErrors, BadQueryParametersAre400WithTheParameter) {
  for (const auto& [query, param] : std::vector<std::pair<std::string, std::string>>{{"limit=0", "?limit"},
                                                                                     {"limit=abc", "?limit"},
                                                                                     {"limit=501", "?limit"},
                                                                                     {"state=done", "?state"},
                                                                                     {"cursor=xyz", "?cursor"},
                                                                                     {"colour=red", "?colour"}}) {
    const HttpReply r = http_request(port(), "GET", "/v1/jobs?" + query);
    EXPECT_TRUE(is_problem(r, 400, "bad-query")) << query;
    EXPECT_EQ(problem_path(r), param) << query;
  }
}

TEST_F(ApiErrors, BadIdempotencyKeyIs400) {
  const HttpReply r = submit_job(port(), image_job(), {{"Idempotency-Key", std::string(300, 'k')}});
  EXPECT_TRUE(is_problem(r, 400, "bad-idempotency-key"));
}

TEST_F(ApiErrors, UnknownThingsAre404) {
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v2/jobs"), 404, "not-found"));
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/job_aaaaaaaaaaaaaaaaaaaaaaaaaa"), 404, "not-found"));
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/../../etc/passwd"), 404, "not-found"));
  EXPECT_TRUE(is_problem(http_request(port(), "DELETE", "/v1/jobs/nonsense"), 404, "not-found"));
  EXPECT_TRUE(
      is_problem(http_request(port(), "GET", "/v1/jobs/job_aaaaaaaaaaaaaaaaaaaaaaaaaa/result"), 404, "not-found"));
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/blobs/sha256:" + std::string(64, '0')), 404, "not-found"));
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/schemas/nope.json"), 404, "not-found"));
  // A succeeded job has no file of another name (and no way out of its folder).
  const HttpReply accepted = submit_job(port(), image_job());
  ASSERT_EQ(accepted.status, 202) << accepted.body;
  const std::string id = accepted.json()["id"];
  EXPECT_EQ(wait_for_job(port(), id)["state"], "succeeded");
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/" + id + "/files/secret.txt"), 404, "not-found"));
  EXPECT_TRUE(
      is_problem(http_request(port(), "GET", "/v1/jobs/" + id + "/files/..%2F..%2Fjobs.sqlite3"), 404, "not-found"));
}

TEST_F(ApiErrors, WrongMethodIs405WithAllow) {
  HttpReply r = http_request(port(), "PUT", "/v1/jobs", "{}");
  EXPECT_TRUE(is_problem(r, 405, "method-not-allowed"));
  EXPECT_EQ(r.header("allow"), "POST, GET");
  r = http_request(port(), "DELETE", "/v1/blobs");
  EXPECT_TRUE(is_problem(r, 405, "method-not-allowed"));
  EXPECT_EQ(r.header("allow"), "POST");
}

TEST_F(ApiErrors, ABodyThatStopsArrivingIs408) {
  RawConnection c(port());
  c.send("POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n{\"ima");
  const auto start = std::chrono::steady_clock::now();
  const HttpReply r = c.read_reply(10);
  EXPECT_TRUE(is_problem(r, 408, "request-timeout"));
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(900));  // --read-timeout 1
}

TEST_F(ApiErrors, ConflictsAre409) {
  // Hold the single worker with a slower job (a large output at a tight tolerance), so that the next one stays queued.
  nlohmann::json slower = image_job(1000);
  slower["warp"]["tolerance_px"] = 1e-5;
  const HttpReply slow = submit_job(port(), slower);
  ASSERT_EQ(slow.status, 202) << slow.body;
  const HttpReply queued = submit_job(port(), image_job());
  ASSERT_EQ(queued.status, 202);
  const std::string id = queued.json()["id"];
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/" + id + "/result"), 409, "no-result"));
  const HttpReply canceled = http_request(port(), "DELETE", "/v1/jobs/" + id);
  EXPECT_EQ(canceled.status, 200) << canceled.body;
  EXPECT_EQ(canceled.json()["state"], "canceled");
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/" + id + "/result"), 409, "no-result"));
  // DELETE of a finished job purges it (no longer 409): gone, files and all.
  EXPECT_EQ(http_request(port(), "DELETE", "/v1/jobs/" + id).status, 204);
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs/" + id), 404, "not-found"));
  const std::string slow_id = slow.json()["id"];
  EXPECT_EQ(wait_for_job(port(), slow_id)["state"], "succeeded");
  EXPECT_EQ(http_request(port(), "DELETE", "/v1/jobs/" + slow_id).status, 204);
  EXPECT_TRUE(is_problem(http_request(port(), "DELETE", "/v1/jobs/" + slow_id), 404, "not-found"));
}

TEST_F(ApiErrors, TheSameIdempotencyKeyWhileTheFirstRequestIsInProgressIs409) {
  const std::string body = image_job().dump();
  const std::string key = "key-in-progress-" + std::to_string(::getpid());
  const std::string head =
      "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nIdempotency-Key: " + key +
      "\r\nContent-Length: " + std::to_string(body.size()) + "\r\n\r\n";
  RawConnection first(port());
  first.send(head + body.substr(0, 10));  // the first request has begun: its body is still arriving
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const HttpReply second = submit_job(port(), image_job(), {{"Idempotency-Key", key}});
  EXPECT_TRUE(is_problem(second, 409, "idempotency-key-in-use"));
  EXPECT_EQ(second.header("retry-after"), "1");
  first.send(body.substr(10));
  const HttpReply done = first.read_reply();
  ASSERT_EQ(done.status, 202) << done.body;
  const HttpReply retry = submit_job(port(), image_job(), {{"Idempotency-Key", key}});
  EXPECT_EQ(retry.status, 202);
  EXPECT_EQ(retry.header("idempotent-replayed"), "true");
  EXPECT_EQ(retry.json()["id"], done.json()["id"]);
}

TEST_F(ApiErrors, TooLargeIs413BeforeOrWhileReading) {
  RawConnection declared(port());
  declared.send(
      "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 2000000\r\n\r\n");
  const HttpReply r = declared.read_reply();
  EXPECT_TRUE(is_problem(r, 413, "body-too-large"));
  EXPECT_THAT(detail(r), HasSubstr("POST /v1/blobs"));
  // Chunked: the size is only known while reading.
  RawConnection chunked(port());
  const std::string chunk(600000, ' ');
  char size[32];
  std::snprintf(size, sizeof size, "%zx\r\n", chunk.size());
  chunked.send(
      "POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nTransfer-Encoding: chunked\r\n\r\n");
  chunked.send(std::string(size) + chunk + "\r\n" + size + chunk + "\r\n");
  EXPECT_TRUE(is_problem(chunked.read_reply(), 413, "body-too-large"));
}

TEST_F(ApiErrors, NotJsonIs415) {
  const HttpReply r = http_request(port(), "POST", "/v1/jobs", image_job().dump(), {}, "text/plain");
  EXPECT_TRUE(is_problem(r, 415, "unsupported-media-type"));
  EXPECT_THAT(detail(r), HasSubstr("application/json"));
}

// An 8×8 grey PNG: one colour channel, no normal map.
std::string grey_png() {
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("texwarp-grey-" + std::to_string(::getpid()) + ".png");
  write_image(file.string(), Image(8, 8, 1), PixelFormat::kUint8);
  std::ifstream in(file, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::filesystem::remove(file);
  return bytes;
}

TEST_F(ApiErrors, InvalidJobsAre422WithTheJsonPath) {
  const auto refused = [&](const nlohmann::json& job) {
    HttpReply r = submit_job(port(), job);
    EXPECT_TRUE(is_problem(r, 422, "invalid-job")) << job.dump().substr(0, 200);
    EXPECT_THAT(detail(r), HasSubstr(problem_path(r)));
    return r;
  };
  nlohmann::json job = image_job();
  job["warp"]["features"][1]["colour"] = "red";
  EXPECT_EQ(problem_path(refused(job)), "$.warp.features[1].colour");

  // What the image holds: an unknown role or filter names its values; an unknown colour space is looked up in
  // OpenColorIO's config when the job is planned, on submission, and refused naming the config's spaces.
  job = image_job();
  job["image"]["role"] = "albedo";
  EXPECT_THAT(detail(refused(job)), HasSubstr(R"(expected "color", "data" or "normal", got "albedo")"));
  job = image_job();
  job["output"] = {{"filter", "ewa"}};
  EXPECT_EQ(problem_path(refused(job)), "$.output.filter");
  job = image_job();
  job["image"]["color_space"] = "ACEScg";
  HttpReply space = refused(job);
  EXPECT_EQ(problem_path(space), "$.image.color_space");
  EXPECT_THAT(detail(space), HasSubstr(R"(unknown colour space "ACEScg")"));
  job = image_job();
  job["image"]["role"] = "normal";
  job["image"]["base64"] = proto::base64_encode(grey_png());
  EXPECT_EQ(problem_path(refused(job)), "$.image.role");

  job = image_job();
  job["warp"]["features"][0]["source"][1] = "16";
  HttpReply r = refused(job);
  EXPECT_EQ(problem_path(r), "$.warp.features[0].source[1]");
  EXPECT_THAT(detail(r), HasSubstr("expected a number, got a string"));

  job = image_job();  // two features whose sources lie closer than the minimum separation
  job["warp"]["prealign"] = "none";
  job["warp"]["features"][0] = {{"id", "l"}, {"source", {10, 30}}, {"target", {50, 30}}};
  job["warp"]["features"][1] = {{"id", "r"}, {"source", {10.2, 30}}, {"target", {10, 60}}};
  r = refused(job);
  EXPECT_EQ(problem_path(r), "$.warp.features");
  EXPECT_THAT(detail(r), HasSubstr("(\"l\") and features[1] (\"r\") come within 0.2 px"));

  job = image_job();
  job["warp"]["alpha"] = 9;
  EXPECT_EQ(problem_path(refused(job)), "$.warp.alpha");

  job = image_job();
  job["image"] = {{"blob", "sha256:" + std::string(64, '7')}};
  r = refused(job);
  EXPECT_EQ(problem_path(r), "$.image.blob");
  EXPECT_THAT(detail(r), HasSubstr("POST /v1/blobs"));

  job["image"] = {{"path", (*dir_ / "elsewhere" / "t.png").string()}};
  EXPECT_EQ(problem_path(refused(job)), "$.image.path");

  job["image"] = {{"base64", proto::base64_encode("this is not an image")}};
  r = refused(job);
  EXPECT_EQ(problem_path(r), "$.image");
  EXPECT_THAT(detail(r), Not(HasSubstr(server_->data_dir().string())));  // never the server's own file layout

  job["image"] = {{"base64", proto::base64_encode(test_png(128))}};  // 16384 pixels > --max-image-megapixels 0.01
  r = refused(job);
  EXPECT_EQ(problem_path(r), "$.image");
  EXPECT_THAT(detail(r), HasSubstr("more than the limit"));

  job = image_job(2000);  // 4 megapixels > --max-output-megapixels 1
  EXPECT_EQ(problem_path(refused(job)), "$.output");

  job = slow_image_job(64);  // 36 features > --max-features 8
  r = refused(job);
  EXPECT_EQ(problem_path(r), "$.warp.features");
  EXPECT_THAT(detail(r), HasSubstr("36 features, more than the limit of 8"));

  job = image_job();
  job["output"]["image"] = false;
  EXPECT_EQ(problem_path(refused(job)), "$.output.image");
}

TEST_F(ApiErrors, AnIdempotencyKeyReusedWithAnotherBodyIs422) {
  const std::string key = "reused-" + std::to_string(::getpid());
  ASSERT_EQ(submit_job(port(), image_job(), {{"Idempotency-Key", key}}).status, 202);
  const HttpReply r = submit_job(port(), image_job(70), {{"Idempotency-Key", key}});
  EXPECT_TRUE(is_problem(r, 422, "idempotency-key-reused"));
}

TEST_F(ApiErrors, OversizedHeaderIs431) {
  const HttpReply r = http_request(port(), "GET", "/v1/jobs", {}, {{"X-Padding", std::string(4000, 'p')}});
  EXPECT_TRUE(is_problem(r, 431, "header-too-large"));
}

TEST_F(ApiErrors, InternalErrorsSayNothingButTheRequestId) {
  const HttpReply accepted = submit_job(port(), image_job());
  const std::string id = accepted.json()["id"];
  ASSERT_EQ(wait_for_job(port(), id)["state"], "succeeded");
  fs::remove(server_->data_dir() / "results" / (id + ".1") / "report.json");  // the disk lost a file under the server
  const HttpReply r = http_request(port(), "GET", "/v1/jobs/" + id + "/result", {}, {{"X-Request-Id", "trace-me-42"}});
  EXPECT_TRUE(is_problem(r, 500, "internal"));
  EXPECT_THAT(detail(r), HasSubstr("trace-me-42"));
  EXPECT_THAT(r.body, Not(HasSubstr("report.json")));
  EXPECT_THAT(r.body, Not(HasSubstr("missing")));
  EXPECT_THAT(r.body, Not(HasSubstr(server_->data_dir().string())));
  EXPECT_THAT(server_->log(), HasSubstr("the report of succeeded job " + id + " is missing"));  // the log has it
}

}  // namespace
}  // namespace texwarp::testing
