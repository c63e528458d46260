// Served results and result folders for the farm tests: see served_results.hpp.
#include "served_results.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <ctime>

#include "raw_http.hpp"
#include "texwarp/server/sha256.hpp"

namespace texwarp::testing {

namespace fs = std::filesystem;

ServedFiles fetch_result_files(unsigned short port, const std::string& id) {
  ServedFiles out;
  const HttpReply result = http_request(port, "GET", "/v1/jobs/" + id + "/result");
  const nlohmann::json r = result.json();
  if (result.status != 200 || !r.is_object() || !r.contains("files") || r["files"].empty()) {
    ADD_FAILURE() << "port " << port << ": no result for " << id << ": " << result.status << " " << result.body;
    ++out.bad;
    return out;
  }
  for (const auto& f : r["files"]) {
    const std::string name = f.value("name", "");
    const HttpReply file = http_request(port, "GET", f.value("href", ""));
    if (file.status != 200 || server::sha256_hex(file.body) != f.value("sha256", "")) {
      ADD_FAILURE() << "port " << port << ": job " << id << " file " << name << ": status " << file.status
                    << ", sha256 " << server::sha256_hex(file.body) << " but the manifest says " << f.dump();
      ++out.bad;
    }
    out.bytes[name] = file.body;
  }
  return out;
}

namespace {

std::vector<std::string> folders_with_prefix(const fs::path& data_dir, const std::string& prefix) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(data_dir / "results", ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

std::vector<std::string> published_result_folders(const fs::path& data_dir, const std::string& id) {
  return folders_with_prefix(data_dir, id + ".");
}

std::vector<std::string> temp_result_folders(const fs::path& data_dir, const std::string& id) {
  return folders_with_prefix(data_dir, ".tmp-" + id + "-");
}

std::vector<nlohmann::json> list_all_jobs(unsigned short port) {
  std::vector<nlohmann::json> jobs;
  std::string cursor;
  for (int page = 0; page < 10000; ++page) {
    const HttpReply reply =
        http_request(port, "GET", "/v1/jobs?limit=500" + (cursor.empty() ? std::string() : "&cursor=" + cursor));
    const nlohmann::json j = reply.json();
    if (reply.status != 200 || !j.is_object() || !j.contains("jobs")) {
      ADD_FAILURE() << "port " << port << ": GET /v1/jobs: " << reply.status << " " << reply.body;
      return jobs;
    }
    for (const auto& s : j["jobs"]) jobs.push_back(s);
    if (!j.contains("next_cursor") || !j["next_cursor"].is_string()) return jobs;
    cursor = j["next_cursor"].get<std::string>();
  }
  ADD_FAILURE() << "port " << port << ": GET /v1/jobs never ended";
  return jobs;
}

std::int64_t epoch_ms(const nlohmann::json& rfc3339) {
  if (!rfc3339.is_string()) return -1;
  std::tm tm{};
  int ms = 0;
  const std::string s = rfc3339.get<std::string>();
  if (std::sscanf(s.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d.%3dZ", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour,
                  &tm.tm_min, &tm.tm_sec, &ms) != 7) {
    return -1;
  }
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  return static_cast<std::int64_t>(::timegm(&tm)) * 1000 + ms;
}

}  // namespace texwarp::testing
