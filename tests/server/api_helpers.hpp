// Calls of texwarpd's API for the end-to-end tests, over raw_http: submit a job, read its status, wait for a state;
// and the result folders a job left in the data folder.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "raw_http.hpp"

namespace texwarp::testing {

HttpReply submit_job(unsigned short port, const nlohmann::json& job, const Headers& headers = {});
nlohmann::json job_status(unsigned short port, const std::string& id);

// Polls until the job's state is terminal (or `state` when given, or progress ≥ min_progress while running);
// returns the last status (the test fails if the time runs out).
nlohmann::json wait_for_job(unsigned short port, const std::string& id, double timeout_s = 60.0);
nlohmann::json wait_for_state(unsigned short port, const std::string& id, const std::string& state,
                              double timeout_s = 60.0, int min_progress = 0);

// The folders under <data_dir>/results/ that belong to job `id` (published "<id>.<epoch>", temporary
// ".tmp-<id>-<epoch>", legacy "<id>"), sorted.
std::vector<std::string> result_folders(const std::filesystem::path& data_dir, const std::string& id);

// True when `reply` is an RFC 9457 problem of this status and type slug, with the request path as instance.
::testing::AssertionResult is_problem(const HttpReply& reply, int status, const std::string& slug);

}  // namespace texwarp::testing
