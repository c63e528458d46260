// JSON bombs and hostile job documents against the real texwarpd: a 32 MiB nesting bomb is refused (400) at once
// with little memory while /livez keeps answering; a repeated key and a mistyped key are 422 with the JSON path.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <iostream>
#include <map>
#include <sstream>

#include "api_helpers.hpp"
#include "process_memory.hpp"
#include "server_process.hpp"
#include "test_jobs.hpp"
#include "test_time.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr std::size_t kBodyBytes = 32u << 20;  // the server's default --max-job-body-mb
// The fix answers in milliseconds; before it, ~30 s (both slower alike where everything is: test_time.hpp).
const double kMaxSeconds = wait_seconds(5.0);
constexpr long kMaxGrowthKiB = 100L * 1024;  // a 32 MiB body is held once or twice; the bombs took 1–2.6 GB

// VmRSS and VmHWM (KiB) of a process.
std::map<std::string, long> memory_kib(pid_t pid) {
  return {{"VmRSS", process_memory_kib(pid, "VmRSS")}, {"VmHWM", process_memory_kib(pid, "VmHWM")}};
}

// `unit` repeated to fill (at most) the largest body the server takes.
std::string bomb(const std::string& unit) {
  std::string text;
  text.reserve(kBodyBytes);
  while (text.size() + unit.size() <= kBodyBytes) text += unit;
  return text;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

class RequestBomb : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test_folder("-suite"));
    server_ = new ServerProcess(*dir_ / "data");
  }
  static void TearDownTestSuite() {
    delete server_;
    fs::remove_all(*dir_);
    delete dir_;
  }
  static unsigned short port() { return server_->port(); }

  // Posts `body` as a job and checks the 400 malformed-json answer, its time and the server's memory growth.
  static void expect_refused_cheaply(const std::string& body, const std::string& detail) {
    const auto before = memory_kib(server_->pid());
    const auto start = std::chrono::steady_clock::now();
    const HttpReply r = http_request(port(), "POST", "/v1/jobs", body);
    const double seconds = seconds_since(start);
    const auto after = memory_kib(server_->pid());
    EXPECT_TRUE(is_problem(r, 400, "malformed-json"));
    EXPECT_EQ(r.json().value("detail", ""), detail);
    EXPECT_LT(seconds, kMaxSeconds);
    if (kResidentMemoryIsMeasured) {
      EXPECT_LT(after.at("VmRSS") - before.at("VmRSS"), kMaxGrowthKiB);
      EXPECT_LT(after.at("VmHWM") - before.at("VmHWM"), kMaxGrowthKiB);
    }
    std::cout << "refused in " << seconds << " s; VmRSS " << before.at("VmRSS") / 1024 << " -> "
              << after.at("VmRSS") / 1024 << " MiB, VmHWM " << before.at("VmHWM") / 1024 << " -> "
              << after.at("VmHWM") / 1024 << " MiB\n";
  }

  static ServerProcess* server_;
  static fs::path* dir_;
};

ServerProcess* RequestBomb::server_ = nullptr;
fs::path* RequestBomb::dir_ = nullptr;

TEST_F(RequestBomb, ArrayNestingBombIsRefusedAtOnceWithLittleMemory) {
  expect_refused_cheaply(bomb("["), "request body: JSON nested deeper than 64 levels (byte 65)");
}

TEST_F(RequestBomb, ObjectNestingBombIsRefusedAtOnceWithLittleMemory) {
  expect_refused_cheaply(bomb(R"({"a":)"), "request body: JSON nested deeper than 64 levels (byte 321)");
}

TEST_F(RequestBomb, LivenessAnswersWhileBombsArrive) {
  const std::string arrays = bomb("[");
  const std::string objects = bomb(R"({"a":)");
  const auto start = std::chrono::steady_clock::now();
  auto first = std::async(std::launch::async, [&] { return http_request(port(), "POST", "/v1/jobs", arrays); });
  auto second = std::async(std::launch::async, [&] { return http_request(port(), "POST", "/v1/jobs", objects); });
  const HttpReply live = http_request(port(), "GET", "/livez");
  EXPECT_EQ(live.status, 200) << live.body;
  EXPECT_LT(seconds_since(start), kMaxSeconds);
  EXPECT_TRUE(is_problem(first.get(), 400, "malformed-json"));
  EXPECT_TRUE(is_problem(second.get(), 400, "malformed-json"));
  EXPECT_LT(seconds_since(start), kMaxSeconds);
  EXPECT_EQ(http_request(port(), "GET", "/livez").status, 200);
}

// A wide body (32 MiB of empty objects in one array) is valid JSON: its parse costs memory in proportion to the
// body (bounded by --max-job-body-mb) but none of it stays once the answer is given.
TEST_F(RequestBomb, AWideBodyLeavesNoMemoryBehind) {
  std::string wide = "[";
  while (wide.size() + 6 <= kBodyBytes) wide += "{},";
  wide += "{}]";
  const auto before = memory_kib(server_->pid());
  const HttpReply r = http_request(port(), "POST", "/v1/jobs", wide);
  const auto after = memory_kib(server_->pid());
  EXPECT_TRUE(is_problem(r, 422, "invalid-job"));
  EXPECT_EQ(r.json().value("detail", ""), "$: expected an object, got an array");
  if (kResidentMemoryIsMeasured) {
    EXPECT_LT(after.at("VmRSS") - before.at("VmRSS"), kMaxGrowthKiB);  // before the heap trim: +680 MB for good
  }
  std::cout << "VmRSS " << before.at("VmRSS") / 1024 << " -> " << after.at("VmRSS") / 1024 << " MiB (peak "
            << after.at("VmHWM") / 1024 << " MiB)\n";
  EXPECT_EQ(http_request(port(), "GET", "/livez").status, 200);
}

// image_job() as text with `extra` (text of more members) added to the object of feature `index`.
std::string job_with_feature_members(std::size_t index, const std::string& extra) {
  nlohmann::json job = image_job();
  nlohmann::json& features = job["warp"]["features"];
  const std::string marker = R"("__marker__":0)";
  features[index]["__marker__"] = 0;
  std::string text = job.dump();
  const auto at = text.find(marker);
  return text.replace(at, marker.size(), extra.substr(1));  // `extra` starts with the separating comma
}

TEST_F(RequestBomb, DuplicateKeyIs422WithItsPath) {
  const HttpReply r = http_request(port(), "POST", "/v1/jobs", job_with_feature_members(2, R"(,"source":[5,5])"));
  EXPECT_TRUE(is_problem(r, 422, "invalid-job"));
  EXPECT_EQ(r.json().value("path", ""), "$.warp.features[2].source");
  EXPECT_EQ(r.json().value("detail", ""), "$.warp.features[2].source: duplicate key");
}

TEST_F(RequestBomb, MistypedKeysAre422WithTheNearName) {
  nlohmann::json job = image_job();
  job["warp"]["featurez"] = job["warp"]["features"];
  job["warp"].erase("features");
  HttpReply r = submit_job(port(), job);
  EXPECT_TRUE(is_problem(r, 422, "invalid-job"));
  EXPECT_EQ(r.json().value("path", ""), "$.warp.features");
  EXPECT_EQ(r.json().value("detail", ""),
            R"($.warp.features: required key is missing (there is an unknown key "featurez"))");

  job = image_job();
  job["warp"].erase("tolerance_px");
  job["warp"]["tolerance_pz"] = 0.01;
  r = submit_job(port(), job);
  EXPECT_TRUE(is_problem(r, 422, "invalid-job"));
  EXPECT_EQ(r.json().value("path", ""), "$.warp.tolerance_pz");
  EXPECT_EQ(r.json().value("detail", ""), R"($.warp.tolerance_pz: unknown key; did you mean "tolerance_px"?)");
}

}  // namespace
}  // namespace texwarp::testing
