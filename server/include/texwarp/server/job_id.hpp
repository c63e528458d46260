// Job ids: "job_" + 26 lowercase base32 characters of 128 random bits (openapi.json's JobId pattern).
#pragma once

#include <string>

namespace texwarp::server {

std::string new_job_id();
bool is_job_id(const std::string& id);

}  // namespace texwarp::server
