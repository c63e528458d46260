// DataDirLock: texwarpd's exclusive hold on its --data-dir (flock on <data-dir>/texwarpd.lock, the holder's PID
// written in it), taken before anything in the folder is touched, so that two servers never share one job store.
// The kernel releases it when the process ends, however it ends.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace texwarp::server {

// Another live process holds the folder's lock; what() names the folder and the holder's PID.
class DataDirInUse : public std::runtime_error {
 public:
  explicit DataDirInUse(const std::string& message) : std::runtime_error(message) {}
};

class DataDirLock {
 public:
  // Creates the folder when missing and takes its lock without waiting. DataDirInUse when another process holds
  // it; std::system_error when the lock file cannot be opened or locked.
  explicit DataDirLock(const std::filesystem::path& data_dir);
  ~DataDirLock();
  DataDirLock(const DataDirLock&) = delete;
  DataDirLock& operator=(const DataDirLock&) = delete;

  // The lock file's name inside the data folder.
  static constexpr const char* kFileName = "texwarpd.lock";

 private:
  int fd_ = -1;
};

}  // namespace texwarp::server
