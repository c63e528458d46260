// Atomic file publication: see atomic_file.hpp.
#include "texwarp/core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace texwarp {
namespace {

namespace fs = std::filesystem;

bool fsync_path(const fs::path& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

}  // namespace

std::string temporary_path_for(const std::string& target) {
  static std::atomic<unsigned> counter{0};
  const fs::path t = fs::absolute(target);
  return (t.parent_path() / ("." + t.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                             std::to_string(counter++) + t.extension().string()))
      .string();
}

void publish_file(const std::string& temporary, const std::string& target) {
  std::error_code ec;
  if (!fsync_path(temporary, false)) {
    fs::remove(temporary, ec);
    throw std::runtime_error(target + ": cannot flush the new file to disk");
  }
  fs::rename(temporary, target, ec);
  if (ec) {
    fs::remove(temporary, ec);
    throw std::runtime_error(target + ": cannot put the new file in place (" + ec.message() + ")");
  }
  fsync_path(fs::absolute(target).parent_path(), true);
}

StagedFiles::~StagedFiles() {
  std::error_code ec;
  for (const auto& [temporary, target] : staged_) fs::remove(temporary, ec);
  // Innermost first; a folder that holds anything else stays (remove fails on it), and whatever is no longer a folder
  // there (a link or a file put in its place) is not ours to remove.
  while (!made_.empty()) {
    if (fs::symlink_status(made_.back(), ec).type() == fs::file_type::directory) fs::remove(made_.back(), ec);
    made_.pop_back();
  }
}

void StagedFiles::make_folder(const std::string& folder) {
  if (folder.empty()) return;
  // The levels create_directories will make, walked as it walks them: each component that names nothing yet (not even
  // a link: a dangling link is the user's, and creating through it fails), remembered where the system puts it (its
  // existing part resolved, symlinks and ".." first: "link/../new" is made beside the link's target, and "m1/../x"
  // makes m1 and x). "." and ".." make nothing.
  std::error_code ec;
  fs::path prefix;
  for (const fs::path& part : fs::absolute(folder)) {
    prefix /= part;
    if (part.empty() || part == "." || part == "..") continue;
    if (fs::symlink_status(prefix, ec).type() != fs::file_type::not_found) continue;
    fs::path level = fs::weakly_canonical(prefix, ec);
    if (ec) level = prefix.lexically_normal();
    // Remembered first, outermost first: a creation that fails part way leaves the levels it made to the destructor
    // too (one that was never made is skipped there).
    made_.push_back(level.string());
  }
  fs::create_directories(folder);
}

std::string StagedFiles::stage(const std::string& target) {
  staged_.emplace_back(temporary_path_for(target), target);
  return staged_.back().first;
}

void StagedFiles::publish_all() {
  made_.clear();  // the folders stay with what is published into them
  while (!staged_.empty()) {
    const auto [temporary, target] = staged_.front();
    staged_.erase(staged_.begin());
    publish_file(temporary, target);
  }
}

}  // namespace texwarp
