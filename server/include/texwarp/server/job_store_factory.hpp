// open_job_store: the JobStore that texwarpd's --store names: "" or "sqlite" (the embedded default, in
// <data-dir>/jobs.sqlite3) or a postgresql:// (postgres://) libpq URI shared by every node.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "texwarp/server/job_store.hpp"

namespace texwarp::server {

// `migrate`: create or upgrade a PostgreSQL schema (SQLite's file is migrated whenever it is opened). Throws
// std::invalid_argument for a --store value that is neither, and what the store's constructor throws (a message
// naming the store, never its password).
std::unique_ptr<JobStore> open_job_store(const std::string& store, const std::filesystem::path& data_dir, bool migrate);

}  // namespace texwarp::server
