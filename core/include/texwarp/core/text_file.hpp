// Whole text files: reading with a size limit (untrusted input), and atomic writing (atomic_file.hpp) so that
// a reader never sees a half-written report, OBJ or certificate.
#pragma once

#include <string>
#include <string_view>

namespace texwarp {

// InputError naming the file when it cannot be opened or is larger than max_bytes.
std::string read_text_file(const std::string& path, long long max_bytes);

// std::runtime_error naming the file when it cannot be written.
void write_text_file_atomically(const std::string& path, std::string_view text);

}  // namespace texwarp
