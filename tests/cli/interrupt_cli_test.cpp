// SIGTERM and SIGINT during `texwarp warp` (a farm scheduler's preemption, Ctrl-C): the real binary, spawned and
// signalled while its pathlines run, must stop at its next tile with exit 3 and a message, and leave its output
// folder as it was (no output, no staged file). Without the handler the signal's default action kills it (no exit
// code, whatever it had staged left behind).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "test_folder.hpp"
#include "texwarp/core/image_io.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

class InterruptCliTest : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    // 1 600 features on a 256² image, every pixel its own pathline (--exact): minutes of work, canceled long before.
    constexpr int kSize = 256;
    Image image(kSize, kSize, 3);
    for (int y = 0; y < kSize; ++y) {
      for (int x = 0; x < kSize; ++x) {
        float* p = image.pixel(x, y);
        p[0] = static_cast<float>(((x / 8) + (y / 8)) % 2);
        p[1] = static_cast<float>(x) / kSize;
        p[2] = static_cast<float>(y) / kSize;
      }
    }
    write_image(path("in.png"), image, PixelFormat::kUint8);
    std::ofstream f(path("f.json"));
    f << R"({"features": [)";
    constexpr int kSide = 40;
    for (int j = 0; j < kSide; ++j) {
      for (int i = 0; i < kSide; ++i) {
        const double x = 20.0 + i * 5.5;
        const double y = 20.0 + j * 5.5;
        f << (i + j > 0 ? "," : "") << "{\"source\": [" << x << ", " << y << "], \"target\": ["
          << x + 3.0 * std::sin(y * 0.02) << ", " << y + 3.0 * std::cos(x * 0.02) << "]}";
      }
    }
    f << "]}";
    fs::create_directories(dir_.path() / "out");
  }

  std::string path(const std::string& name) const { return (dir_.path() / name).string(); }

  std::string err_text() const {
    std::ifstream in(path("stderr.txt"));
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  texwarp::testing::TestFolder dir_{"interrupt"};
};

// The largest "progress N%" the command has printed, or -1.
int last_progress(const std::string& err) {
  static const std::regex kLine("progress (\\d+)%");
  int last = -1;
  for (auto it = std::sregex_iterator(err.begin(), err.end(), kLine); it != std::sregex_iterator(); ++it) {
    last = std::max(last, std::stoi((*it)[1].str()));
  }
  return last;
}

TEST_P(InterruptCliTest, ASignalWhilePathlinesRunStopsTheWarpAndWritesNothing) {
  const int signal = GetParam();
  const std::string out = path("out/warped.png");
  std::vector<std::string> args = {TEXWARP_CLI,    "warp",  "--features", path("f.json"), "--in",
                                   path("in.png"), "--out", out,          "--exact",      "--progress"};
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, path("stderr.txt").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  // The signals at their default in the child, whatever this test inherited (a background job of a non-interactive
  // shell starts with SIGINT ignored), as a user at a terminal has them.
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, argv[0], &actions, &attributes, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);

  // Until the pathlines have run a while (the command's progress moves past the plan and the device's set-up).
  const auto start = Clock::now();
  int status = 0;
  bool exited = false;
  while (Clock::now() - start < std::chrono::seconds(300)) {
    if (waitpid(pid, &status, WNOHANG) == pid) {
      exited = true;
      break;
    }
    if (Clock::now() - start > std::chrono::seconds(2) && last_progress(err_text()) >= 3) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_FALSE(exited) << "it ended before the signal: " << err_text();
  const int progress_at_signal = last_progress(err_text());
  ASSERT_GE(progress_at_signal, 3) << err_text();
  ASSERT_LT(progress_at_signal, 100) << err_text();

  const auto signalled = Clock::now();
  ASSERT_EQ(::kill(pid, signal), 0);
  while (Clock::now() - signalled < std::chrono::seconds(60)) {
    if (waitpid(pid, &status, WNOHANG) == pid) {
      exited = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!exited) {
    ::kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
    FAIL() << "still running 60 s after the signal: " << err_text();
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - signalled).count();
  ASSERT_TRUE(WIFEXITED(status)) << "ended by the signal itself, not by the handler; " << err_text();
  EXPECT_EQ(WEXITSTATUS(status), 3) << err_text();
  EXPECT_NE(err_text().find("texwarp: warp: interrupted; no output was written"), std::string::npos) << err_text();
  EXPECT_LT(seconds, 45.0) << "the work stops at its next tile (a few seconds at most here)";
  // The output folder as it was: empty.
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir_.path() / "out")) left.push_back(e.path().filename().string());
  EXPECT_TRUE(left.empty()) << left.size() << " files left, the first " << (left.empty() ? "" : left.front());
}

std::string signal_name(const ::testing::TestParamInfo<int>& p) { return p.param == SIGTERM ? "Sigterm" : "Sigint"; }

INSTANTIATE_TEST_SUITE_P(Signals, InterruptCliTest, ::testing::Values(SIGTERM, SIGINT), signal_name);

}  // namespace
}  // namespace texwarp
