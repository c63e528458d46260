// Text file reading and atomic writing: see text_file.hpp.
#include "texwarp/core/text_file.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "texwarp/core/atomic_file.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {

std::string read_text_file(const std::string& path, long long max_bytes) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(InputLocation::file(path), "cannot open the file (" + ec.message() + ")");
  if (static_cast<long long>(size) > max_bytes) {
    throw InputError(InputLocation::file(path), "the file is " + std::to_string(size) +
                                                    " bytes, more than the limit of " + std::to_string(max_bytes));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(InputLocation::file(path), "cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text_file_atomically(const std::string& path, std::string_view text) {
  const std::string temporary = temporary_path_for(path);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot create a file in its folder");
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) {
      out.close();
      std::error_code ec;
      std::filesystem::remove(temporary, ec);
      throw std::runtime_error(path + ": write failed");
    }
  }
  publish_file(temporary, path);
}

}  // namespace texwarp
