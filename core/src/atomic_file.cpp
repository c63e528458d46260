// Atomic file publication: see atomic_file.hpp.
#include "texwarp/core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <stdexcept>
#include <system_error>

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
}

std::string StagedFiles::stage(const std::string& target) {
  staged_.emplace_back(temporary_path_for(target), target);
  return staged_.back().first;
}

void StagedFiles::publish_all() {
  while (!staged_.empty()) {
    const auto [temporary, target] = staged_.front();
    staged_.erase(staged_.begin());
    publish_file(temporary, target);
  }
}

}  // namespace texwarp
