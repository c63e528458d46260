// What a texwarpd node serves of a job and what lies in the shared data folder, for the farm tests: a succeeded
// job's files fetched from a node and checked against its manifest, the result folders of a job on disk, every job
// a node lists, and the API's RFC 3339 timestamps as epoch milliseconds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace texwarp::testing {

// A succeeded job's result as one node serves it: file name → bytes.
struct ServedFiles {
  std::map<std::string, std::string> bytes;
  int bad = 0;  // files missing, not 200, or whose SHA-256 differs from the manifest's (each one a test failure)
};

// GET /v1/jobs/{id}/result, then every file it lists; each file is checked against the manifest's sha256.
ServedFiles fetch_result_files(unsigned short port, const std::string& id);

// The job's published result folders under <data_dir>/results (`<id>.<epoch>`), sorted (api_helpers' result_folders
// lists its temporary ones too).
std::vector<std::string> published_result_folders(const std::filesystem::path& data_dir, const std::string& id);
// The job's temporary result folders (`.tmp-<id>-<epoch>`), sorted.
std::vector<std::string> temp_result_folders(const std::filesystem::path& data_dir, const std::string& id);

// Every job the node lists (all pages, newest first).
std::vector<nlohmann::json> list_all_jobs(unsigned short port);

// "2026-11-30T19:00:00.123Z" → epoch milliseconds (-1 when it is not such a timestamp).
std::int64_t epoch_ms(const nlohmann::json& rfc3339);

}  // namespace texwarp::testing
