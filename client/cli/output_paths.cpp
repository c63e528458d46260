// Outputs checked before a command's work: see output_paths.hpp.
#include "output_paths.hpp"

#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace texwarp::cli {
namespace {

namespace fs = std::filesystem;

bool writable(const fs::path& folder) { return ::access(folder.c_str(), W_OK) == 0; }

}  // namespace

void check_output_file(const std::string& flag, const std::string& path) {
  if (path.empty()) return;
  const fs::path folder = fs::absolute(path).parent_path();
  std::error_code ec;
  std::string why;
  if (fs::is_directory(folder, ec)) {
    if (!writable(folder)) why = "no permission to write in " + folder.string();
  } else if (ec && ec != std::errc::no_such_file_or_directory) {
    why = folder.string() + ": " + ec.message();
  } else {
    why = folder.string() + (fs::exists(fs::symlink_status(folder, ec)) ? " is not a folder" : " does not exist");
  }
  if (!why.empty()) throw std::runtime_error(flag + " " + path + ": cannot write there (" + why + ")");
}

void check_output_folder(const std::string& flag, const std::string& folder) {
  if (folder.empty()) return;
  const fs::path target = fs::absolute(folder);
  std::error_code ec;
  // The deepest level that names something, a link to nothing included (as create_directories meets it).
  fs::path level = target;
  while (fs::symlink_status(level, ec).type() == fs::file_type::not_found && level.has_relative_path()) {
    level = level.parent_path();
  }
  std::errc why{};
  if (fs::is_directory(level, ec)) {
    if (level != target && !writable(level)) why = std::errc::permission_denied;
  } else {
    why = level == target || fs::is_symlink(fs::symlink_status(level, ec)) ? std::errc::file_exists
                                                                           : std::errc::not_a_directory;
  }
  if (why != std::errc{}) {
    throw std::runtime_error(flag + " " + folder + ": cannot make the folder (" + std::make_error_code(why).message() +
                             ")");
  }
}

}  // namespace texwarp::cli
