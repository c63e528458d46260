// Job ids: "job_" + 26 lowercase base32 characters of 128 random bits (openapi.json's JobId pattern), and the
// error for an id this server has no job of.
#pragma once

#include <string>

#include "texwarp/server/service_error.hpp"

namespace texwarp::server {

std::string new_job_id();
bool is_job_id(const std::string& id);
// kNotFound, naming (a prefix of) the id.
ServiceError job_not_found(const std::string& id);

}  // namespace texwarp::server
