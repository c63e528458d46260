// A fresh folder for the running test: <temp>/texwarp-<prefix>-<pid>-<suite>.<test> (a parameterised test's '/'
// as '_'), emptied when made; TestFolder removes it again when it goes, test_folder_path leaves that to the caller.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>

#include <gtest/gtest.h>

namespace texwarp::testing {

// The folder's path, made empty (created, or emptied when a previous run left it).
inline std::filesystem::path test_folder_path(const std::string& prefix) {
  namespace fs = std::filesystem;
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "no-test";
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  const fs::path dir =
      fs::temp_directory_path() / ("texwarp-" + prefix + "-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

class TestFolder {
 public:
  explicit TestFolder(const std::string& prefix) : path_(test_folder_path(prefix)) {}
  ~TestFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  TestFolder(const TestFolder&) = delete;
  TestFolder& operator=(const TestFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // A path in the folder (a std::filesystem::path converts to the std::string that file functions take).
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace texwarp::testing
