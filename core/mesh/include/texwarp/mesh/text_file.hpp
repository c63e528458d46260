// Whole text files: reading with a size limit, and atomic writing (temporary file in the same folder, flush,
// rename) so that a reader never sees a half-written OBJ or report.
#pragma once

#include <string>
#include <string_view>

namespace texwarp::mesh {

// InputError naming the file when it cannot be opened or is larger than max_bytes.
std::string read_text_file(const std::string& path, long long max_bytes);

// std::runtime_error when the file cannot be written.
void write_text_file_atomically(const std::string& path, std::string_view text);

}  // namespace texwarp::mesh
