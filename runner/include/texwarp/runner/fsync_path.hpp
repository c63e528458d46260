// fsync of a file or a folder, for publishing a whole folder of results durably (core/atomic_file.hpp publishes
// single files): the folder's files, then the folder, then its parent after the rename that publishes it.
#pragma once

#include <filesystem>

namespace texwarp::runner {

// std::runtime_error (with errno's text) when the path cannot be opened or synced.
void fsync_path(const std::filesystem::path& path);

}  // namespace texwarp::runner
