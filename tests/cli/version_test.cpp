// `texwarp --version` and `texwarpd --version`: one line "PROGRAM VERSION (commit COMMIT)" on stdout, exit 0, where
// VERSION is the project() VERSION of the top-level CMakeLists.txt and COMMIT is `git rev-parse --short HEAD` of the
// source tree the binaries were built from ("unknown" when it is no git checkout).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "shell_command.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

using testing::run_shell;

// The VERSION of `project(texwarp VERSION X.Y.Z ...)` in the top-level CMakeLists.txt, read here independently of
// the build's plumbing.
std::string project_version() {
  std::ifstream in(fs::path(TEXWARP_SOURCE_DIR) / "CMakeLists.txt");
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  std::smatch m;
  return std::regex_search(s, m, std::regex(R"(project\(texwarp VERSION ([0-9]+\.[0-9]+\.[0-9]+))")) ? m[1].str() : "";
}

// What the commit must read: `git rev-parse --short HEAD` of the source tree; "unknown" when it is no git checkout;
// empty when it is one but git cannot say (then the commit is not checked).
std::string expected_commit() {
  if (!fs::exists(fs::path(TEXWARP_SOURCE_DIR) / ".git")) return "unknown";
  const auto git = run_shell("git -C '" + std::string(TEXWARP_SOURCE_DIR) + "' rev-parse --short HEAD 2>/dev/null");
  if (git.status != 0 || git.output.empty()) return "";
  return git.output.substr(0, git.output.find('\n'));
}

void check_version_line(const std::string& program, const std::string& binary) {
  // stderr goes to stdout's end, so that anything printed besides the line fails the exact match below.
  const auto o = run_shell("'" + binary + "' --version 2>&1");
  EXPECT_EQ(o.status, 0) << o.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_match(
      o.output, m, std::regex(program + R"( ([0-9]+\.[0-9]+\.[0-9]+) \(commit ([0-9a-f]{4,40}|unknown)\)\n)")))
      << "got: \"" << o.output << "\"";
  const std::string version = project_version();
  ASSERT_FALSE(version.empty()) << "no project(texwarp VERSION ...) in CMakeLists.txt";
  EXPECT_EQ(m[1].str(), version);
  const std::string commit = expected_commit();
  if (commit.empty()) GTEST_SKIP() << "a git checkout whose commit git cannot read here";
  EXPECT_EQ(m[2].str(), commit) << "(a stale binary? rebuild after committing)";
}

TEST(Version, TexwarpPrintsItsVersionAndCommit) { check_version_line("texwarp", TEXWARP_CLI); }

TEST(Version, TexwarpdPrintsItsVersionAndCommit) { check_version_line("texwarpd", TEXWARPD_BINARY); }

}  // namespace
}  // namespace texwarp
