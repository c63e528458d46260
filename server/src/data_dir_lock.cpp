// The exclusive lock on texwarpd's data folder: see data_dir_lock.hpp.
#include "texwarp/server/data_dir_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <string>
#include <system_error>
#include <thread>

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;

// The PID the holder wrote, "" when it has not written it (it writes right after taking the lock).
std::string holder_pid(int fd) {
  for (int attempt = 0; attempt < 50; ++attempt) {
    char text[32] = {};
    const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
    std::string pid;
    for (ssize_t i = 0; i < n && text[i] >= '0' && text[i] <= '9'; ++i) pid.push_back(text[i]);
    if (!pid.empty() && n > 0 && text[n - 1] == '\n') return pid;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return {};
}

}  // namespace

DataDirLock::DataDirLock(const fs::path& data_dir) {
  fs::create_directories(data_dir);
  const fs::path file = data_dir / kFileName;
  fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "cannot open the lock file " + file.string());
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    if (error == EWOULDBLOCK) {
      const std::string pid = holder_pid(fd_);
      ::close(fd_);
      fd_ = -1;
      throw DataDirInUse("--data-dir " + data_dir.string() + " is in use by texwarpd (pid " +
                         (pid.empty() ? std::string("unknown") : pid) + "); stop it or use another folder");
    }
    ::close(fd_);
    fd_ = -1;
    throw std::system_error(error, std::generic_category(), "cannot lock " + file.string());
  }
  // Overwritten in place, then cut: on a full disk this needs no new block. Without it the lock still holds (a
  // second instance then names no PID), so a failure here does not stop the start.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::pwrite(fd_, pid.data(), pid.size(), 0) == static_cast<ssize_t>(pid.size())) {
    [[maybe_unused]] const int cut = ::ftruncate(fd_, static_cast<off_t>(pid.size()));
  }
}

DataDirLock::~DataDirLock() {
  // The file stays (removing it would race with a process that has just opened it); closing releases the lock.
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace texwarp::server
