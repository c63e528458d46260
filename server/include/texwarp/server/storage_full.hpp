// A full data folder: how texwarpd recognises one (ENOSPC or EDQUOT as SQLite, the blob store, std::filesystem and
// Beast report it), how much space is left, and the error a request refused because of it gets.
#pragma once

#include <cstdint>
#include <exception>
#include <filesystem>
#include <string>

#include <boost/system/error_code.hpp>

#include "texwarp/server/service_error.hpp"

namespace texwarp::server {

bool is_storage_full(const std::exception& e);
bool is_storage_full(const boost::system::error_code& ec);

// Bytes free for an unprivileged writer in the file system of `folder` (0 when it cannot be asked).
std::uint64_t free_bytes_of(const std::filesystem::path& folder);

// kStorageFull: `what` says what was not stored ("the blob was not stored").
ServiceError storage_full_error(const std::string& what);

}  // namespace texwarp::server
