// SmallFilesystem: a real, tiny filesystem (tmpfs of a given size) mounted on a fresh test folder, so that tests
// can fill it and see what the server does when the disk is full. Needs the right to mount (root, as in CI);
// available() is false elsewhere and the test says so when it skips.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace texwarp::testing {

class SmallFilesystem {
 public:
  explicit SmallFilesystem(std::uint64_t bytes);
  ~SmallFilesystem();  // unmounts
  SmallFilesystem(const SmallFilesystem&) = delete;
  SmallFilesystem& operator=(const SmallFilesystem&) = delete;

  bool available() const { return mounted_; }
  const std::string& why_not() const { return why_not_; }
  const std::filesystem::path& path() const { return path_; }
  // Writes a file of filler bytes until the filesystem is full (ENOSPC), leaving `keep_free` bytes when > 0.
  void fill(std::uint64_t keep_free = 0);
  // Removes the filler so that writes succeed again.
  void release();
  std::uint64_t free_bytes() const;

 private:
  std::filesystem::path path_;
  bool mounted_ = false;
  std::string why_not_;
};

}  // namespace texwarp::testing
