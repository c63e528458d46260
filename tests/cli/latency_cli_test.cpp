// The whole command as users time it (issue 15): --timings names the stages of the one list and they fit in the
// wall time; a trivial warp opens no device; the PNG level changes the file, never the pixels; --progress is
// monotone and ends at 100 %; compiled kernels are kept in the cache folder and a corrupt entry is rebuilt.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>

#include <nlohmann/json.hpp>

#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/latency_stage.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int code = -1;
  std::string err;
};

class LatencyCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("texwarp-latency-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    // A 96×64 RGB texture with detail (a PNG compresses it differently at each level).
    Image image(96, 64, 3);
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
      image.pixels[i] = static_cast<float>(static_cast<double>(i * 37 % 101) / 100.0);
    write_image(path("in.png"), image, PixelFormat::kUint8);
    write("none.json", R"({"features": []})");
    write("moved.json", R"({"tolerance_px": 0.01, "features": [
      {"source": [20, 20], "target": [24, 18]}, {"source": [70, 24], "target": [68, 30]},
      {"source": [40, 50], "target": [44, 46]}]})");
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  void write(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }

  // `env`: assignments put before the command ("A=1 B=2 ").
  CliRun run(const std::string& args, const std::string& env = "") const {
    const std::string err = path("stderr.txt");
    const std::string cmd = env + std::string(TEXWARP_CLI) + " " + args + " >/dev/null 2>" + err;
    const int status = std::system(cmd.c_str());
    CliRun r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(err);
    std::stringstream ss;
    ss << in.rdbuf();
    r.err = ss.str();
    return r;
  }

  // The JSON line --timings=json prints.
  static nlohmann::json timings_of(const std::string& err) {
    std::istringstream lines(err);
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("{\"timings\"", 0) == 0) return nlohmann::json::parse(line)["timings"];
    }
    ADD_FAILURE() << "no timings line in:\n" << err;
    return nlohmann::json::object();
  }

  fs::path dir_;
};

// Every stage named is one of the list's, none is negative, and together they fit in the wall time.
void expect_consistent(const nlohmann::json& timings) {
  double sum = 0.0;
  for (const auto& [name, seconds] : timings["stages"].items()) {
    EXPECT_TRUE(proto::enum_from_name<proto::LatencyStage>(name).has_value()) << name;
    EXPECT_GE(seconds.get<double>(), 0.0) << name;
    sum += seconds.get<double>();
  }
  EXPECT_GT(timings["wall_s"].get<double>(), 0.0);
  EXPECT_LE(sum, timings["wall_s"].get<double>() + 0.011);  // + one clock tick of the process's start time
}

TEST_F(LatencyCliTest, TimingsNameTheStagesAndFitInTheWallTime) {
  const CliRun r = run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " +
                       path("out.png") + " --timings=json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json t = timings_of(r.err);
  expect_consistent(t);
  for (const char* stage :
       {"startup", "plan", "device_setup", "decode", "pathlines", "sampling", "verify", "encode", "write"}) {
    EXPECT_TRUE(t["stages"].contains(stage)) << stage << ": " << t.dump();
  }
  const CliRun table = run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " +
                           path("out.png") + " --timings");
  ASSERT_EQ(table.code, 0) << table.err;
  EXPECT_NE(table.err.find("texwarp: timings (s)"), std::string::npos) << table.err;
  EXPECT_NE(table.err.find("  pathlines"), std::string::npos) << table.err;
  EXPECT_EQ(run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " + path("out.png") +
                " --timings=yaml")
                .code,
            2);
}

TEST_F(LatencyCliTest, AnIdentityWarpTakesTheClosedFormAndOpensNoDevice) {
  // No OpenCL device can be opened with no ICD: an identity warp must not need one.
  const CliRun r = run("warp --features " + path("none.json") + " --in " + path("in.png") + " --out " +
                           path("out.png") + " --timings=json",
                       "OCL_ICD_VENDORS=" + path("no-icds") + " ");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("closed form: 0 pathlines"), std::string::npos) << r.err;
  const nlohmann::json t = timings_of(r.err);
  expect_consistent(t);
  EXPECT_FALSE(t["stages"].contains("device_setup")) << t.dump();
  // The same without the closed form needs the device, and fails without one: the environment above is real.
  EXPECT_EQ(run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " + path("out.png"),
                "OCL_ICD_VENDORS=" + path("no-icds") + " ")
                .code,
            1);
  // The closed form's pixels are the source's (identity, bilinear at pixel centres).
  const Image in = read_image(path("in.png"));
  const Image out = read_image(path("out.png"));
  ASSERT_EQ(out.channels, in.channels + 1);  // coverage alpha
  for (std::size_t p = 0; p < static_cast<std::size_t>(in.width) * in.height; ++p) {
    for (int c = 0; c < in.channels; ++c) ASSERT_EQ(out.pixels[p * 4 + c], in.pixels[p * 3 + c]) << p;
    ASSERT_EQ(out.pixels[p * 4 + 3], 1.0f) << p;
  }
}

TEST_F(LatencyCliTest, PngLevelChangesTheFileNotThePixels) {
  for (const int level : {0, 9}) {
    const CliRun r = run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " +
                         path("level" + std::to_string(level) + ".png") + " --png-level " + std::to_string(level));
    ASSERT_EQ(r.code, 0) << r.err;
  }
  EXPECT_GT(fs::file_size(path("level0.png")), fs::file_size(path("level9.png")) * 3 / 2);
  EXPECT_EQ(read_image(path("level0.png")).pixels, read_image(path("level9.png")).pixels);
  const CliRun bad = run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " +
                         path("x.png") + " --png-level 10");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--png-level"), std::string::npos) << bad.err;
  for (const char* compression : {"none", "small"}) {
    const CliRun r = run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " +
                         path(std::string(compression) + ".tif") + " --compression " + compression);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  EXPECT_GT(fs::file_size(path("none.tif")), fs::file_size(path("small.tif")));
  EXPECT_EQ(read_image(path("none.tif")).pixels, read_image(path("small.tif")).pixels);
}

TEST_F(LatencyCliTest, ProgressIsMonotoneAndReaches100OnlyAtTheEnd) {
  const CliRun r = run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " +
                       path("out.png") + " --exact --progress");
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<int> percents;
  std::istringstream lines(r.err);
  const std::regex progress("progress (\\d+)%");
  std::size_t after_last_progress = 0;
  std::size_t index = 0;
  for (std::string line; std::getline(lines, line); ++index) {
    std::smatch m;
    if (std::regex_match(line, m, progress)) {
      percents.push_back(std::stoi(m[1]));
      after_last_progress = index + 1;
    }
  }
  ASSERT_GE(percents.size(), 3u) << r.err;
  for (std::size_t i = 1; i < percents.size(); ++i) EXPECT_LE(percents[i - 1], percents[i]) << r.err;
  EXPECT_EQ(percents.back(), 100);
  EXPECT_LT(percents[percents.size() - 2], 100) << "100% before the end:\n" << r.err;
  // Only the summary line follows the last progress line: nothing ran after 100 %.
  EXPECT_EQ(index - after_last_progress, 1u) << r.err;
}

// "N compiled, M from the cache, K cache files rebuilt" of `texwarp warm`.
std::array<int, 3> warm_counts(const std::string& err) {
  std::smatch m;
  const std::regex counts("\\((\\d+) compiled, (\\d+) from the cache, (\\d+) cache files rebuilt\\)");
  if (!std::regex_search(err, m, counts)) {
    ADD_FAILURE() << err;
    return {-1, -1, -1};
  }
  return {std::stoi(m[1]), std::stoi(m[2]), std::stoi(m[3])};
}

TEST_F(LatencyCliTest, KernelsAreCachedAcrossProcessesAndACorruptEntryIsRebuilt) {
  const std::string env = "TEXWARP_CACHE_DIR=" + path("cache") + " POCL_CACHE_DIR=" + path("pocl") + " ";
  const CliRun first = run("warm", env);
  ASSERT_EQ(first.code, 0) << first.err;
  const auto [compiled, from_cache, rebuilt] = warm_counts(first.err);
  EXPECT_GT(compiled, 0) << first.err;
  EXPECT_EQ(from_cache, 0) << first.err;
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(path("cache") + "/programs")) entries.push_back(e.path());
  ASSERT_EQ(static_cast<int>(entries.size()), compiled);

  // A second process builds nothing: every program comes from the cache folder.
  const CliRun second = run("warm", env);
  ASSERT_EQ(second.code, 0) << second.err;
  EXPECT_EQ(warm_counts(second.err), (std::array<int, 3>{0, compiled, 0})) << second.err;

  // One entry truncated (its own format says so), one whose binary the driver refuses (the file is well formed,
  // the binary is garbage): both are built again and replaced, the rest load.
  fs::resize_file(entries[0], fs::file_size(entries[0]) / 2);
  if (entries.size() > 1) {
    std::ifstream in(entries[1], std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    in.close();
    const std::size_t key_at = std::string("texwarp-program-cache 1\n").size();
    ASSERT_EQ(bytes.rfind("texwarp-program-cache 1\n", 0), 0u);
    std::uint64_t key_size = 0;
    for (int i = 0; i < 8; ++i) key_size |= std::uint64_t{static_cast<unsigned char>(bytes[key_at + i])} << (8 * i);
    std::string garbage = bytes.substr(0, key_at + 8 + key_size);
    for (int i = 0; i < 8; ++i) garbage.push_back(static_cast<char>(i == 0 ? 64 : 0));
    garbage += std::string(64, 'Z');
    std::ofstream(entries[1], std::ios::binary | std::ios::trunc) << garbage;
  }
  const CliRun third = run("warm", env);
  ASSERT_EQ(third.code, 0) << third.err;
  const auto after = warm_counts(third.err);
  EXPECT_EQ(after[0] + after[1], compiled) << third.err;
  EXPECT_EQ(after[0], entries.size() > 1 ? 2 : 1) << third.err;
  EXPECT_EQ(after[2], entries.size() > 1 ? 1 : 0) << third.err;  // the driver's refusal, counted
  // And the cache is whole again.
  EXPECT_EQ(warm_counts(run("warm", env).err), (std::array<int, 3>{0, compiled, 0}));
  // A warp after warm works from the cache.
  const CliRun warp =
      run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " + path("out.png"), env);
  EXPECT_EQ(warp.code, 0) << warp.err;
}

}  // namespace
}  // namespace texwarp
