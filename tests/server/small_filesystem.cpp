// A tmpfs of a given size on a test folder: see small_filesystem.hpp.
#include "small_filesystem.hpp"

#include <fcntl.h>
#include <sys/mount.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "server_process.hpp"

namespace texwarp::testing {

SmallFilesystem::SmallFilesystem(std::uint64_t bytes) : path_(test_folder("smallfs")) {
  const std::string options = "size=" + std::to_string(bytes) + ",mode=0755";
  if (::mount("tmpfs", path_.c_str(), "tmpfs", MS_NOSUID | MS_NODEV, options.c_str()) == 0) {
    mounted_ = true;
  } else {
    why_not_ = std::string("cannot mount a tmpfs (needs root): ") + std::strerror(errno);
  }
}

SmallFilesystem::~SmallFilesystem() {
  if (mounted_) ::umount2(path_.c_str(), MNT_DETACH);
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

void SmallFilesystem::fill(std::uint64_t keep_free) {
  const std::string filler = (path_ / ".filler").string();
  const int fd = ::open(filler.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd < 0) return;
  std::vector<char> block(64 << 10, 'x');
  for (;;) {
    const std::uint64_t free = free_bytes();
    if (free <= keep_free) break;
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(block.size(), free - keep_free));
    if (::write(fd, block.data(), n) <= 0) break;
  }
  ::fsync(fd);
  ::close(fd);
}

void SmallFilesystem::release() {
  std::error_code ec;
  std::filesystem::remove(path_ / ".filler", ec);
}

std::uint64_t SmallFilesystem::free_bytes() const {
  struct statvfs vfs {};
  if (::statvfs(path_.c_str(), &vfs) != 0) return 0;
  return static_cast<std::uint64_t>(vfs.f_bavail) * vfs.f_frsize;
}

}  // namespace texwarp::testing
