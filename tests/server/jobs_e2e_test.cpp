// Jobs through the real texwarpd over HTTP: an image job's whole life (its warped image checked pixel by pixel
// against an independent run of the core), blobs, server-side paths, a mesh job, a job that fails while running,
// cancellation, paging, idempotent replays, bearer auth, metrics, readiness and the served API documents.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include "api_helpers.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"
#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/server/sha256.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

Image decode_png(const std::string& bytes, const fs::path& dir) {
  const fs::path file = dir / "decoded.png";
  std::ofstream(file, std::ios::binary) << bytes;
  return read_image(file.string());
}

// The sRGB transfer functions, written out here (IEC 61966-2-1) to check the server's.
double decode_srgb(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }
double encode_srgb(double v) { return v <= 0.0031308 ? v * 12.92 : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055; }

// The warped image as the core computes it here, independently of the server: f⁻¹ of every output pixel centre,
// then the source sampled there (bilinear, transparent border; with `srgb` in linear light, encoded back).

Image expected_warp(const nlohmann::json& job, const Image& source, int width, int height, bool srgb = false) {
  const proto::WarpSpec spec = proto::decode_warp_spec(job["warp"]);
  const WarpProblem problem(features_from_spec(spec), options_from_spec(spec));
  CpuBackend backend;
  std::vector<Point> centres;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) centres.emplace_back(x + 0.5, y + 0.5);
  }
  map_points(backend, problem, centres, Direction::kInverse);
  Image out(width, height, 4, 3);
  Image with_alpha(source.width, source.height, 4, 3);
  for (int y = 0; y < source.height; ++y) {
    for (int x = 0; x < source.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        const double v = source.pixel(x, y)[c];
        with_alpha.pixel(x, y)[c] = static_cast<float>(srgb ? decode_srgb(v) : v);
      }
      with_alpha.pixel(x, y)[3] = 1.0f;
    }
  }
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      float* px = out.pixel(x, y);
      sample_image(with_alpha, centres[static_cast<std::size_t>(y) * width + x], Interpolation::kBilinear,
                   Border::kTransparent, px);
      if (srgb && px[3] > 0.0f) {
        for (int c = 0; c < 3; ++c) px[c] = static_cast<float>(encode_srgb(px[c] / px[3]) * px[3]);
      }
    }
  }
  return out;
}

// Polls /readyz until it says ready (a worker opens its device just after the server starts listening).
nlohmann::json until_ready(unsigned short port) {
  nlohmann::json ready;
  for (int i = 0; i < 1000; ++i) {
    ready = http_request(port, "GET", "/readyz").json();
    if (ready.value("status", "") == "ready") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return ready;
}

class JobsE2E : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test_folder(); }
  void TearDown() override {
    server_.reset();
    fs::remove_all(dir_);
  }
  ServerProcess& start(const std::vector<std::string>& args = {}, std::vector<std::string> env = {}) {
    server_ = std::make_unique<ServerProcess>(dir_ / "data", args, std::move(env));
    return *server_;
  }
  unsigned short port() const { return server_->port(); }

  fs::path dir_;
  std::unique_ptr<ServerProcess> server_;
};

TEST_F(JobsE2E, ImageJobFromSubmitToItsWarpedPixels) {
  start();
  nlohmann::json job = image_job();
  // A pathline per pixel, tight enough that the server's pathlines and this test's agree far below a level of the
  // checkerboard's edges.
  job["warp"]["tolerance_px"] = 1e-7;
  job["options"] = {{"exact", true}};
  // The PNG's default role (colour, sRGB: interpolated in linear light), sampled at each pixel's position (the
  // footprint filter has its own closed-form tests).
  job["output"] = {{"filter", "point"}};
  const HttpReply accepted = submit_job(port(), job);
  ASSERT_EQ(accepted.status, 202) << accepted.body;
  const nlohmann::json queued = accepted.json();
  const std::string id = queued["id"];
  EXPECT_EQ(accepted.header("location"), "/v1/jobs/" + id);
  EXPECT_EQ(queued["kind"], "image");
  EXPECT_EQ(queued["name"], "test image job");
  // A worker may start the job before the 202 is written: queued (not started yet) or already under way.
  EXPECT_TRUE(queued["state"] == "queued" ? queued["started_at"].is_null() : queued["started_at"].is_string())
      << queued.dump();

  const nlohmann::json done = wait_for_job(port(), id);
  ASSERT_EQ(done["state"], "succeeded") << done.dump();
  EXPECT_EQ(done["progress"], 100);
  EXPECT_EQ(done["attempts"], 1);
  EXPECT_TRUE(done["error"].is_null());
  EXPECT_LE(done["created_at"].get<std::string>(), done["started_at"].get<std::string>());
  EXPECT_LE(done["started_at"].get<std::string>(), done["finished_at"].get<std::string>());
  EXPECT_EQ(done["links"]["result"], "/v1/jobs/" + id + "/result");

  const HttpReply result = http_request(port(), "GET", "/v1/jobs/" + id + "/result");
  ASSERT_EQ(result.status, 200) << result.body;
  const nlohmann::json r = result.json();
  ASSERT_EQ(r["files"].size(), 2u);
  EXPECT_EQ(r["files"][0]["name"], "warped.png");
  EXPECT_EQ(r["files"][1]["name"], "report.json");
  EXPECT_EQ(r["report"]["kind"], "image");
  EXPECT_EQ(r["report"]["backend"], "cpu");
  EXPECT_EQ(r["report"]["method"], "per_pixel");
  EXPECT_EQ(r["report"]["certificate"]["exact"], true);
  EXPECT_LT(r["report"]["residuals"]["max_px"].get<double>(), 1e-6);
  EXPECT_EQ(r["report"]["residuals"]["per_feature"].size(), 4u);
  const nlohmann::json& sampling = r["report"]["output"]["sampling"];
  EXPECT_EQ(sampling["role"], "color");
  EXPECT_EQ(sampling["color_space"], "sRGB");
  EXPECT_EQ(sampling["filter"], "point");
  EXPECT_EQ(sampling["footprint_pixels"], 0);

  std::string png;
  for (const auto& f : r["files"]) {
    const HttpReply file = http_request(port(), "GET", f["href"]);
    ASSERT_EQ(file.status, 200);
    EXPECT_EQ(file.header("content-type"), f["media_type"]);
    EXPECT_EQ(file.body.size(), f["bytes"].get<std::size_t>());
    EXPECT_EQ(server::sha256_hex(file.body), f["sha256"]);
    EXPECT_EQ(file.header("etag"), "\"" + f["sha256"].get<std::string>() + "\"");
    if (f["name"] == "warped.png") png = file.body;
    const HttpReply head = http_request(port(), "HEAD", f["href"]);
    EXPECT_EQ(head.status, 200);
    EXPECT_EQ(head.header("content-length"), std::to_string(file.body.size()));
    // A client holding the file gets 304.
    EXPECT_EQ(http_request(port(), "GET", f["href"], {}, {{"If-None-Match", file.header("etag")}}).status, 304);
  }
  const Image warped = decode_png(png, dir_);
  const Image source = decode_png(test_png(64), dir_);
  ASSERT_EQ(warped.width, 64);
  ASSERT_EQ(warped.channels, 4);  // transparent border: alpha added
  const Image expected = expected_warp(job, source, 64, 64, true);
  double max_diff = 0.0;
  int opaque = 0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      // Where the output is partly transparent the file holds unassociated 8-bit colour: compare coverage there.
      const bool whole = expected.pixel(x, y)[3] > 0.999f;
      opaque += whole ? 1 : 0;
      for (int c = whole ? 0 : 3; c < 4; ++c) {
        max_diff = std::max(max_diff, static_cast<double>(std::abs(expected.pixel(x, y)[c] - warped.pixel(x, y)[c])));
      }
    }
  }
  EXPECT_GT(opaque, 3000);
  EXPECT_LE(max_diff, 1.0 / 255.0);  // 8-bit quantisation only
  // And the warp is not the identity: the content moved.
  double moved = 0.0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x)
      moved = std::max(moved, static_cast<double>(std::abs(warped.pixel(x, y)[1] - source.pixel(x, y)[1])));
  }
  EXPECT_GT(moved, 1.0 / 64.0);
}

TEST_F(JobsE2E, TheDefaultCertifiedLatticeMeetsItsTolerance) {
  start();
  nlohmann::json job = image_job(256);
  job["warp"]["tolerance_px"] = 1e-7;
  job["options"] = {{"tolerance_px", 0.05}};
  // The lattice's tolerance on the file's own values, each sampled at its position.
  job["image"]["role"] = "data";
  job["output"]["filter"] = "point";
  const HttpReply accepted = submit_job(port(), job);
  ASSERT_EQ(accepted.status, 202) << accepted.body;
  const std::string id = accepted.json()["id"];
  ASSERT_EQ(wait_for_job(port(), id)["state"], "succeeded");
  const nlohmann::json report = http_request(port(), "GET", "/v1/jobs/" + id + "/result").json()["report"];
  EXPECT_EQ(report["method"], "certified_lattice");
  const nlohmann::json& c = report["certificate"];
  EXPECT_EQ(c["exact"], false);
  EXPECT_EQ(c["tolerance_px"], 0.05);
  EXPECT_LE(c["max_error_px_sampled"].get<double>(), 0.05);
  EXPECT_LE(c["max_error_px_estimated"].get<double>(), 0.05);
  EXPECT_GT(c["min_jacobian_det"].get<double>(), 0.0);
  EXPECT_EQ(c["nonpositive_jacobians"], 0);
  EXPECT_LT(c["pathlines"].get<int>(), 256 * 256 / 4);  // far fewer pathlines than pixels
  // Against the exact warp computed here: within the tolerance times the texture's steepest slope (the
  // checkerboard's edges: 0.8 per pixel at 64² upscaled 4× → 0.2 per output pixel), plus quantisation.
  const Image warped = decode_png(http_request(port(), "GET", "/v1/jobs/" + id + "/files/warped.png").body, dir_);
  const Image expected = expected_warp(job, decode_png(test_png(64), dir_), 256, 256);
  double max_diff = 0.0;
  for (int y = 0; y < 256; ++y) {
    for (int x = 0; x < 256; ++x) {
      if (expected.pixel(x, y)[3] < 0.999f) continue;
      for (int ch = 0; ch < 3; ++ch) {
        max_diff = std::max(max_diff, static_cast<double>(std::abs(expected.pixel(x, y)[ch] - warped.pixel(x, y)[ch])));
      }
    }
  }
  EXPECT_LE(max_diff, 0.05 * 0.8 + 1.0 / 255.0);
}

TEST_F(JobsE2E, TheShippedExampleJobsRunAsTheyAreOnAServerWithItsDefaults) {
  server_ =
      std::make_unique<ServerProcess>(dir_ / "data", std::vector<std::string>{}, std::vector<std::string>{}, false);
  for (const char* name : {"astronaut-job.json", "sheet-mesh-job.json"}) {
    std::ifstream in(fs::path(TEXWARP_SOURCE_DIR) / "examples" / name, std::ios::binary);
    std::stringstream body;
    body << in.rdbuf();
    const HttpReply accepted = http_request(port(), "POST", "/v1/jobs", body.str());  // the file's bytes, as they are
    ASSERT_EQ(accepted.status, 202) << name << ": " << accepted.body;
    const nlohmann::json done = wait_for_job(port(), accepted.json()["id"], 120);
    EXPECT_EQ(done["state"], "succeeded") << name << ": " << done.dump();
    const nlohmann::json report =
        http_request(port(), "GET", "/v1/jobs/" + done["id"].get<std::string>() + "/result").json()["report"];
    EXPECT_EQ(report["backend"], runner::default_device()) << name;
    EXPECT_EQ(report["certificate"]["nonpositive_jacobians"], 0) << name;
  }
}

TEST_F(JobsE2E, AFullQueueIs429WithRetryAfter) {
  start({"--max-queue", "1", "--threads-per-job", "1"});
  const std::string running = submit_job(port(), slow_image_job(400)).json()["id"];
  wait_for_state(port(), running, "running", 30);
  ASSERT_EQ(submit_job(port(), image_job()).status, 202);  // waits in the queue (length 1)
  const HttpReply full = submit_job(port(), image_job());
  EXPECT_TRUE(is_problem(full, 429, "queue-full"));
  EXPECT_GE(std::stoi(full.header("retry-after")), 1);
  EXPECT_EQ(http_request(port(), "DELETE", "/v1/jobs/" + running).status, 202);
}

TEST_F(JobsE2E, ConfigFileAndRetention) {
  std::ofstream(dir_ / "texwarpd.toml") << "max-queue = 3\nretention-hours = 0.0003\nworkers = 2\n";
  start({"--config", (dir_ / "texwarpd.toml").string()});
  const nlohmann::json ready = until_ready(port());
  EXPECT_EQ(ready["checks"]["queue"]["max"], 3);
  const std::string id = submit_job(port(), image_job()).json()["id"];
  ASSERT_EQ(wait_for_job(port(), id)["state"], "succeeded");
  EXPECT_EQ(result_folders(server_->data_dir(), id), std::vector<std::string>{id + ".1"});  // run under lease epoch 1
  // Retention of ~1 s, swept every second: the row goes first, then the files, then the log says so.
  bool swept = false;
  for (int i = 0; i < 400 && !swept; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    swept = server_->log().find("retention: deleted finished jobs") != std::string::npos;
  }
  EXPECT_TRUE(swept);
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs/" + id).status, 404);
  EXPECT_TRUE(result_folders(server_->data_dir(), id).empty());
}

TEST_F(JobsE2E, BlobsAreContentAddressedAndDeduplicated) {
  start();
  const std::string png = test_png(64);
  const HttpReply first = http_request(port(), "POST", "/v1/blobs", png, {}, "application/octet-stream");
  ASSERT_EQ(first.status, 201) << first.body;
  const std::string id = first.json()["id"];
  EXPECT_EQ(id, "sha256:" + server::sha256_hex(png));
  EXPECT_EQ(first.json()["bytes"], png.size());
  EXPECT_EQ(first.header("location"), "/v1/blobs/" + id);
  const HttpReply second = http_request(port(), "POST", "/v1/blobs", png, {}, "application/octet-stream");
  EXPECT_EQ(second.status, 200);
  EXPECT_EQ(second.json()["created"], false);
  const HttpReply head = http_request(port(), "HEAD", "/v1/blobs/" + id);
  EXPECT_EQ(head.status, 200);
  EXPECT_EQ(head.header("content-length"), std::to_string(png.size()));
  EXPECT_EQ(http_request(port(), "GET", "/v1/blobs/" + id).body, png);

  nlohmann::json job = image_job();
  job["image"] = {{"blob", id}};
  const HttpReply accepted = submit_job(port(), job);
  ASSERT_EQ(accepted.status, 202) << accepted.body;
  EXPECT_EQ(wait_for_job(port(), accepted.json()["id"])["state"], "succeeded");
}

TEST_F(JobsE2E, ServerSidePathsUnderAnInputRoot) {
  fs::create_directories(dir_ / "textures");
  std::ofstream(dir_ / "textures" / "t.png", std::ios::binary) << test_png(64);
  start({"--input-root", (dir_ / "textures").string()});
  nlohmann::json job = image_job();
  job["image"] = {{"path", (dir_ / "textures" / "t.png").string()}};
  const HttpReply accepted = submit_job(port(), job);
  ASSERT_EQ(accepted.status, 202) << accepted.body;
  EXPECT_EQ(wait_for_job(port(), accepted.json()["id"])["state"], "succeeded");
}

TEST_F(JobsE2E, MeshJobGivesObjUvsWarpedTextureAndReport) {
  start();
  const HttpReply accepted = submit_job(port(), mesh_job());
  ASSERT_EQ(accepted.status, 202) << accepted.body;
  const std::string id = accepted.json()["id"];
  const nlohmann::json done = wait_for_job(port(), id);
  ASSERT_EQ(done["state"], "succeeded") << done.dump();
  const nlohmann::json r = http_request(port(), "GET", "/v1/jobs/" + id + "/result").json();
  std::vector<std::string> names;
  for (const auto& f : r["files"]) names.push_back(f["name"]);
  EXPECT_EQ(names, (std::vector<std::string>{"mesh.obj", "uvs.json", "warped.png", "report.json"}));
  EXPECT_EQ(r["report"]["kind"], "mesh");
  EXPECT_EQ(r["report"]["region"]["vertices"], 49);
  EXPECT_EQ(r["report"]["flipped_triangles"], 0);
  EXPECT_LT(r["report"]["max_residual_px"].get<double>(), 1.0);
  const std::string obj = http_request(port(), "GET", "/v1/jobs/" + id + "/files/mesh.obj").body;
  std::istringstream lines(obj);
  int vt = 0;
  int faces = 0;
  for (std::string line; std::getline(lines, line);) {
    vt += line.rfind("vt ", 0) == 0 ? 1 : 0;
    faces += line.rfind("f ", 0) == 0 ? 1 : 0;
  }
  EXPECT_EQ(vt, 49);
  EXPECT_EQ(faces, 72);
  const nlohmann::json uvs = http_request(port(), "GET", "/v1/jobs/" + id + "/files/uvs.json").json();
  EXPECT_EQ(uvs["uv_origin"], "bottom_left");
  ASSERT_EQ(uvs["uv"].size(), 49u);
  // The feature at vertex 24 (grid point (3, 3)) has its texture source (33, 31): u = x / 64, v = 1 − y / 64.
  const auto& vertices = uvs["vertices"];
  const auto at = std::find(vertices.begin(), vertices.end(), 24) - vertices.begin();
  EXPECT_NEAR(uvs["uv"][at][0].get<double>(), 33.0 / 64.0, 1.0 / 64.0);
  EXPECT_NEAR(uvs["uv"][at][1].get<double>(), 1.0 - 31.0 / 64.0, 1.0 / 64.0);
}

TEST_F(JobsE2E, AJobThatFailsWhileRunningSaysWhyAndWhere) {
  start();
  nlohmann::json job = mesh_job();
  job["mesh"]["region"] = {{"faces", {0, 71}}};  // two triangles that do not touch: not a disk
  const HttpReply accepted = submit_job(port(), job);
  ASSERT_EQ(accepted.status, 202) << accepted.body;
  const nlohmann::json done = wait_for_job(port(), accepted.json()["id"]);
  ASSERT_EQ(done["state"], "failed");
  EXPECT_EQ(done["error"]["type"], "urn:texwarp:problem:invalid-job");
  EXPECT_EQ(done["error"]["path"], "$.mesh.region");
  EXPECT_THAT(done["error"]["detail"].get<std::string>(), HasSubstr("not a single disk"));
  EXPECT_TRUE(result_folders(server_->data_dir(), done["id"].get<std::string>()).empty());
}

TEST_F(JobsE2E, CancelARunningJob) {
  start({"--threads-per-job", "1"});
  const HttpReply accepted = submit_job(port(), slow_image_job(600));
  ASSERT_EQ(accepted.status, 202);
  const std::string id = accepted.json()["id"];
  wait_for_state(port(), id, "running", 30, 4);
  const HttpReply cancel = http_request(port(), "DELETE", "/v1/jobs/" + id);
  EXPECT_EQ(cancel.status, 202) << cancel.body;
  EXPECT_EQ(cancel.json()["cancel_requested"], true);
  const auto start_wait = std::chrono::steady_clock::now();
  const nlohmann::json done = wait_for_job(port(), id, 30);
  EXPECT_LT(std::chrono::steady_clock::now() - start_wait, std::chrono::seconds(3));  // stops at the next tile
  EXPECT_EQ(done["state"], "canceled");
  EXPECT_LT(done["progress"].get<int>(), 100);
  EXPECT_FALSE(done["finished_at"].is_null());
  EXPECT_TRUE(result_folders(server_->data_dir(), id).empty());
  // The worker is free again.
  const HttpReply next = submit_job(port(), image_job());
  EXPECT_EQ(wait_for_job(port(), next.json()["id"])["state"], "succeeded");
}

TEST_F(JobsE2E, ListingPagesThroughEveryJobNewestFirst) {
  start();
  std::vector<std::string> ids;
  ids.reserve(5);
  for (int i = 0; i < 5; ++i) ids.push_back(submit_job(port(), image_job()).json()["id"]);
  for (const auto& id : ids) wait_for_job(port(), id);
  std::vector<std::string> seen;
  std::string cursor;
  int pages = 0;
  do {
    const nlohmann::json page =
        http_request(port(), "GET", "/v1/jobs?limit=2" + (cursor.empty() ? "" : "&cursor=" + cursor)).json();
    for (const auto& j : page["jobs"]) seen.push_back(j["id"]);
    cursor = page["next_cursor"].is_null() ? "" : page["next_cursor"].get<std::string>();
    ++pages;
  } while (!cursor.empty() && pages < 10);
  EXPECT_EQ(pages, 3);
  EXPECT_EQ(seen, std::vector<std::string>(ids.rbegin(), ids.rend()));
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs?state=succeeded").json()["jobs"].size(), 5u);
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs?state=queued").json()["jobs"].size(), 0u);
}

TEST_F(JobsE2E, AnIdempotentRetryReturnsTheSameJob) {
  start();
  const HttpReply first = submit_job(port(), image_job(), {{"Idempotency-Key", "farm-task-17"}});
  ASSERT_EQ(first.status, 202);
  EXPECT_EQ(first.header("idempotent-replayed"), "");
  wait_for_job(port(), first.json()["id"]);
  // The same body with other whitespace and key order is the same request.
  nlohmann::json same = image_job();
  const HttpReply retry = http_request(port(), "POST", "/v1/jobs", same.dump(2), {{"Idempotency-Key", "farm-task-17"}});
  EXPECT_EQ(retry.status, 202);
  EXPECT_EQ(retry.header("idempotent-replayed"), "true");
  EXPECT_EQ(retry.json()["id"], first.json()["id"]);
  EXPECT_EQ(retry.json()["state"], "succeeded");
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs").json()["jobs"].size(), 1u);
}

TEST_F(JobsE2E, BearerTokenFromAFileOrTheEnvironment) {
  std::ofstream(dir_ / "token") << "s3cret-token\n";
  start({"--token-file", (dir_ / "token").string()});
  EXPECT_EQ(http_request(port(), "GET", "/livez").status, 200);
  EXPECT_EQ(http_request(port(), "GET", "/readyz").status, 200);
  HttpReply r = http_request(port(), "GET", "/v1/jobs");
  EXPECT_TRUE(is_problem(r, 401, "unauthorized"));
  EXPECT_EQ(r.header("www-authenticate"), "Bearer realm=\"texwarpd\"");
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/metrics"), 401, "unauthorized"));
  EXPECT_TRUE(is_problem(http_request(port(), "GET", "/v1/jobs", {}, {{"Authorization", "Bearer wrong"}}), 401,
                         "unauthorized"));
  EXPECT_TRUE(is_problem(submit_job(port(), image_job(), {{"Authorization", "Basic czNjcmV0"}}), 401, "unauthorized"));
  r = submit_job(port(), image_job(), {{"Authorization", "Bearer s3cret-token"}});
  EXPECT_EQ(r.status, 202) << r.body;
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs", {}, {{"Authorization", "Bearer s3cret-token"}}).status, 200);

  server_.reset();
  fs::remove_all(dir_ / "data");
  start({}, {"TEXWARPD_TOKEN=from-env"});
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs").status, 401);
  EXPECT_EQ(http_request(port(), "GET", "/v1/jobs", {}, {{"Authorization", "Bearer from-env"}}).status, 200);
}

TEST_F(JobsE2E, MetricsReadinessAndApiDocuments) {
  start();
  const HttpReply accepted = submit_job(port(), image_job());
  wait_for_job(port(), accepted.json()["id"]);
  http_request(port(), "GET", "/v1/jobs/job_aaaaaaaaaaaaaaaaaaaaaaaaaa");
  const HttpReply metrics = http_request(port(), "GET", "/metrics");
  ASSERT_EQ(metrics.status, 200);
  EXPECT_EQ(metrics.header("content-type"), "text/plain; version=0.0.4; charset=utf-8");
  EXPECT_THAT(metrics.body, HasSubstr("texwarpd_jobs_finished_total{kind=\"image\",state=\"succeeded\"} 1\n"));
  EXPECT_THAT(metrics.body, HasSubstr("texwarpd_jobs_submitted_total{kind=\"image\"} 1\n"));
  EXPECT_THAT(metrics.body,
              HasSubstr("texwarpd_http_requests_total{route=\"/v1/jobs\",method=\"POST\",status=\"202\"} 1\n"));
  EXPECT_THAT(metrics.body, HasSubstr("route=\"/v1/jobs/{id}\",method=\"GET\",status=\"404\"} 1\n"));
  EXPECT_THAT(metrics.body, HasSubstr("texwarpd_queue_length 0\n"));
  EXPECT_THAT(metrics.body, HasSubstr("texwarpd_job_run_seconds_count{kind=\"image\"} 1\n"));

  const nlohmann::json ready = until_ready(port());
  EXPECT_EQ(ready["status"], "ready");
  EXPECT_EQ(ready["checks"]["store"], "ok");
  // HEAD answers the same header with no body: the next answer on the connection follows right after it.
  RawConnection keep_alive(port());
  keep_alive.send("HEAD /readyz HTTP/1.1\r\nHost: x\r\n\r\n");
  const HttpReply head = keep_alive.read_reply();
  EXPECT_EQ(head.status, 200);
  EXPECT_GT(std::stoi(head.header("content-length")), 10);
  keep_alive.send("GET /livez HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(keep_alive.read_reply().json()["status"], "ok");
  EXPECT_EQ(ready["checks"]["device"]["status"], "ok");
  EXPECT_EQ(ready["checks"]["device"]["name"], "cpu");

  // The OpenAPI document as served: proto/schema/openapi.json bundled with its schemas, every $ref within it
  // (tests/server/generate_client.sh lints it and generates a client from it).
  const fs::path source_dir = fs::path(TEXWARP_SOURCE_DIR) / "proto" / "schema";
  std::ifstream in(source_dir / "openapi.json");
  const nlohmann::json source = nlohmann::json::parse(in);
  const HttpReply openapi = http_request(port(), "GET", "/v1/openapi.json");
  EXPECT_EQ(openapi.status, 200);
  const nlohmann::json served = openapi.json();
  EXPECT_EQ(served["openapi"], source["openapi"]);
  EXPECT_EQ(served["paths"].size(), source["paths"].size());
  for (const auto& [path, item] : source["paths"].items()) EXPECT_TRUE(served["paths"].contains(path)) << path;
  std::ifstream job_schema(source_dir / "job.schema.json");
  EXPECT_EQ(served["components"]["schemas"]["Job"]["properties"].size(),
            nlohmann::json::parse(job_schema)["properties"].size());
  int refs = 0;
  const std::function<void(const nlohmann::json&)> visit = [&](const nlohmann::json& j) {
    if (j.is_object() && j.contains("$ref")) {
      ++refs;
      const std::string ref = j["$ref"];
      EXPECT_TRUE(ref.rfind("#/", 0) == 0 && served.contains(nlohmann::json::json_pointer(ref.substr(1)))) << ref;
    }
    if (j.is_structured()) {
      for (const auto& child : j) visit(child);
    }
  };
  visit(served);
  EXPECT_GT(refs, 100);
  for (const auto& name :
       {"job.schema.json", "job-status.schema.json", "job-result.schema.json", "problem.schema.json"}) {
    const HttpReply schema = http_request(port(), "GET", std::string("/v1/schemas/") + name);
    EXPECT_EQ(schema.status, 200) << name;
    EXPECT_EQ(schema.json()["$id"], name);  // as in proto/schema/: its $refs resolve under /v1/schemas/
  }
}

TEST_F(JobsE2E, ReadinessChecksTheDefaultDevice) {
  start({"--device", runner::default_device()});
  const nlohmann::json ready = until_ready(port());
  EXPECT_EQ(ready["status"], "ready") << ready.dump();
  EXPECT_EQ(ready["checks"]["device"]["status"], "ok");
  EXPECT_EQ(ready["checks"]["device"]["name"], runner::default_device());
}

}  // namespace
}  // namespace texwarp::testing
