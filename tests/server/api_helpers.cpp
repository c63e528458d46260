// API calls for end-to-end tests: see api_helpers.hpp.
#include <gtest/gtest.h>

#include "api_helpers.hpp"

#include <algorithm>
#include <chrono>
#include <thread>

#include "test_time.hpp"

namespace texwarp::testing {

HttpReply submit_job(unsigned short port, const nlohmann::json& job, const Headers& headers) {
  return http_request(port, "POST", "/v1/jobs", job.dump(), headers);
}

std::vector<std::string> result_folders(const std::filesystem::path& data_dir, const std::string& id) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(data_dir / "results", ec)) {
    const std::string name = e.path().filename().string();
    if (name == id || name.rfind(id + ".", 0) == 0 || name.rfind(".tmp-" + id + "-", 0) == 0) out.push_back(name);
  }
  std::sort(out.begin(), out.end());
  return out;
}

nlohmann::json job_status(unsigned short port, const std::string& id) {
  return http_request(port, "GET", "/v1/jobs/" + id).json();
}

nlohmann::json wait_for_state(unsigned short port, const std::string& id, const std::string& state, double timeout_s,
                              int min_progress) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_seconds(timeout_s));
  nlohmann::json s;
  for (;;) {
    s = job_status(port, id);
    const std::string now = s.is_object() ? s.value("state", "") : "";
    const bool terminal = now == "succeeded" || now == "failed" || now == "canceled";
    if (state.empty() ? terminal : (now == state && s.value("progress", 0) >= min_progress)) return s;
    if (!state.empty() && terminal && now != state) {
      ADD_FAILURE() << "job " << id << " ended " << now << " while waiting for " << state << ": " << s.dump();
      return s;
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ADD_FAILURE() << "job " << id << " still " << s.dump() << " after " << wait_seconds(timeout_s) << " s";
      return s;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

nlohmann::json wait_for_job(unsigned short port, const std::string& id, double timeout_s) {
  return wait_for_state(port, id, "", timeout_s);
}

::testing::AssertionResult is_problem(const HttpReply& reply, int status, const std::string& slug) {
  const nlohmann::json j = reply.json();
  if (reply.status != status) {
    return ::testing::AssertionFailure() << "status " << reply.status << " instead of " << status << ": " << reply.body;
  }
  if (reply.header("content-type") != "application/problem+json") {
    return ::testing::AssertionFailure() << "content type " << reply.header("content-type");
  }
  if (!j.is_object() || j.value("type", "") != "urn:texwarp:problem:" + slug || j.value("status", 0) != status ||
      j.value("title", "").empty() || j.value("detail", "").empty()) {
    return ::testing::AssertionFailure() << "not the expected problem (" << slug << "): " << reply.body;
  }
  if (reply.header("x-request-id").empty()) return ::testing::AssertionFailure() << "no X-Request-Id";
  return ::testing::AssertionSuccess();
}

}  // namespace texwarp::testing
