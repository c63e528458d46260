// Atomic file publication: write to a temporary file beside the target, fsync it, rename it over the target
// and fsync the folder, so that a reader sees the old file or the whole new one, never a part.
#pragma once

#include <string>

namespace texwarp {

// A fresh hidden path in the target's folder that keeps the target's extension (file-format detection).
std::string temporary_path_for(const std::string& target);

// fsyncs `temporary`, renames it to `target`, fsyncs the folder. On failure removes `temporary` and throws
// std::runtime_error naming the target.
void publish_file(const std::string& temporary, const std::string& target);

}  // namespace texwarp
