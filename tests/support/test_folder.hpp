// A fresh folder for the running test: <temp>/texwarp-<prefix>-<pid>-<suite>.<test> (a parameterised test's '/'
// as '_'), emptied when made; TestFolder removes it again when it goes. A folder from test_folder_path stays while
// its test runs and, when the test failed, after it (its logs and files are the evidence); a passed test's is
// removed once the test has ended (its fixture and processes gone). Folders made outside a test (a suite's set-up)
// are the caller's to remove.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <gtest/gtest.h>

namespace texwarp::testing {

namespace detail {

// Removes the folders test_folder_path made for a test when that test passed; registered once per test binary.
class PassedTestFolders final : public ::testing::EmptyTestEventListener {
 public:
  static PassedTestFolders& instance() {
    static PassedTestFolders* const kListener = [] {
      auto* l = new PassedTestFolders;
      ::testing::UnitTest::GetInstance()->listeners().Append(l);  // owned by GoogleTest from here
      return l;
    }();
    return *kListener;
  }
  void add(const std::filesystem::path& dir) { folders_.push_back(dir); }

  void OnTestEnd(const ::testing::TestInfo& info) override {
    if (info.result() != nullptr && info.result()->Passed()) {
      for (const auto& dir : folders_) {
        std::error_code ignored;
        std::filesystem::remove_all(dir, ignored);
      }
    }
    folders_.clear();
  }

 private:
  std::vector<std::filesystem::path> folders_;
};

}  // namespace detail

// Removes `path` (a file or a folder) once the running test has ended passed, as test_folder_path's folders; outside
// a test, nothing.
inline void remove_when_passed(const std::filesystem::path& path) {
  if (::testing::UnitTest::GetInstance()->current_test_info() != nullptr)
    detail::PassedTestFolders::instance().add(path);
}

// The folder's path, made empty (created, or emptied when a previous run left it).
inline std::filesystem::path test_folder_path(const std::string& prefix) {
  namespace fs = std::filesystem;
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "no-test";
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  fs::path dir = fs::temp_directory_path() / ("texwarp-" + prefix + "-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  if (info) detail::PassedTestFolders::instance().add(dir);
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
