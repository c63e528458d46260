// The whole command as users time it (issue 15): --timings names the stages of the one list and they fit in the
// wall time; a trivial warp opens no device; the PNG level changes the file, never the pixels; --progress is
// monotone and ends at 100 %; after `texwarp warm` a new process compiles no kernel.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "test_folder.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/latency_stage.hpp"
#include "texwarp/runner/stage_costs.hpp"

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

  // The startup seconds of --timings=json's line.
  static double startup_of(const CliRun& r) { return timings_of(r.err)["stages"]["startup"].get<double>(); }

  // The JSON line --timings=json prints.
  static nlohmann::json timings_of(const std::string& err) {
    std::istringstream lines(err);
    for (std::string line; std::getline(lines, line);) {
      if (line.rfind("{\"timings\"", 0) == 0) return nlohmann::json::parse(line)["timings"];
    }
    ADD_FAILURE() << "no timings line in:\n" << err;
    return nlohmann::json::object();
  }

  texwarp::testing::TestFolder dir_{"latency"};
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

// The percents of the 'progress N%' lines, in order.
std::vector<int> progress_percents(const std::string& err) {
  std::vector<int> percents;
  std::istringstream lines(err);
  const std::regex progress("progress (\\d+)%");
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (std::regex_match(line, m, progress)) percents.push_back(std::stoi(m[1]));
  }
  return percents;
}

// The progress is weighted by the stages' predicted seconds (runner/stage_costs.hpp), startup by its measured
// ones: the first line is startup's share of the default workload's prediction; once the plan knows the work, the
// progress moves to startup's and plan's share of this warp's prediction; the later stages still move it.
TEST_F(LatencyCliTest, ProgressIsWeightedByPredictedStageSeconds) {
  const CliRun r = run("warp --features " + path("moved.json") + " --in " + path("in.png") + " --out " +
                       path("out.png") + " --exact --progress --timings=json");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<int> percents = progress_percents(r.err);
  ASSERT_GE(percents.size(), 3u) << r.err;
  const double startup = timings_of(r.err)["stages"]["startup"].get<double>();
  using proto::LatencyStage;
  const std::vector<LatencyStage> order = {LatencyStage::kStartup,   LatencyStage::kPlan,   LatencyStage::kDeviceSetup,
                                           LatencyStage::kPathlines, LatencyStage::kVerify, LatencyStage::kDecode,
                                           LatencyStage::kSampling,  LatencyStage::kEncode, LatencyStage::kWrite};
  // Startup's and plan's shares of the predicted whole.
  auto shares = [&](const runner::StageWorkload& work) {
    double total = 0.0;
    for (const LatencyStage s : order) {
      total += s == LatencyStage::kStartup ? std::max(startup, 1e-3) : runner::predicted_seconds(s, work);
    }
    return std::pair(std::max(startup, 1e-3) / total, runner::predicted_seconds(LatencyStage::kPlan, work) / total);
  };
  const auto [first_startup, first_plan] = shares(runner::StageWorkload{});
  EXPECT_NEAR(percents.front(), std::floor(100.0 * first_startup), 1.0) << r.err;
  ImageHeader header;
  header.width = 96;
  header.height = 64;
  const auto [startup_share, plan_share] = shares(runner::image_workload(header, 0, 0, 3, true));
  const int after_plan = static_cast<int>(std::floor(100.0 * (startup_share + plan_share)));
  ASSERT_GT(after_plan, percents.front()) << "this warp's startup share is larger than the default workload's";
  EXPECT_TRUE(std::any_of(percents.begin(), percents.end(), [&](int p) { return std::abs(p - after_plan) <= 1; }))
      << "no line at " << after_plan << "%:\n"
      << r.err;
  // Device set-up, pathlines and the rest cover the remainder: lines between that and 100 %.
  EXPECT_TRUE(std::any_of(percents.begin(), percents.end(), [&](int p) { return p > after_plan + 1 && p < 100; }))
      << r.err;
  EXPECT_TRUE(std::is_sorted(percents.begin(), percents.end())) << r.err;
  EXPECT_EQ(percents.back(), 100);
}

// A texture set's maps (warp --in … --out-dir): the progress moves map by map through their stages, which interleave
// (each map read, sampled, encoded and written in turn): from where the output grid's check leaves it, a line as
// each map is sampled and as it is written, not one jump to the end of all the maps' sampling at the first.
TEST_F(LatencyCliTest, ATextureSetsProgressMovesMapByMap) {
  constexpr int kMaps = 4;
  Image image(512, 512, 3);
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = static_cast<float>(static_cast<double>(i * 37 % 101) / 100.0);
  std::string inputs;
  for (int m = 0; m < kMaps; ++m) {
    const std::string name = "map" + std::to_string(m) + ".png";
    write_image(path(name), image, PixelFormat::kUint8);
    inputs += " --in " + path(name);
  }
  write("set.json", R"({"features": [{"source": [100, 100], "target": [120, 90]},
      {"source": [400, 150], "target": [380, 170]}, {"source": [250, 400], "target": [260, 380]}]})");
  const CliRun r = run("warp --backend cpu --features " + path("set.json") + inputs + " --out-dir " + path("set") +
                       " --progress --timings=json");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<int> percents = progress_percents(r.err);
  EXPECT_TRUE(std::is_sorted(percents.begin(), percents.end())) << r.err;
  EXPECT_EQ(percents.back(), 100) << r.err;
  // Where the maps begin: the predicted shares of every stage before them, this set's workload.
  using proto::LatencyStage;
  ImageHeader header;
  header.width = 512;
  header.height = 512;
  runner::StageWorkload work = runner::image_workload(header, 0, 0, 3, false);
  work.maps = kMaps;
  double total = std::max(startup_of(r), 1e-3);
  double before_maps = total;
  for (const LatencyStage s :
       {LatencyStage::kPlan, LatencyStage::kDeviceSetup, LatencyStage::kPathlines, LatencyStage::kVerify,
        LatencyStage::kDecode, LatencyStage::kSampling, LatencyStage::kEncode, LatencyStage::kWrite}) {
    total += runner::predicted_seconds(s, work);
    if (s == LatencyStage::kPlan || s == LatencyStage::kDeviceSetup || s == LatencyStage::kPathlines ||
        s == LatencyStage::kVerify) {
      before_maps += runner::predicted_seconds(s, work);
    }
  }
  const int maps_start = static_cast<int>(std::floor(100.0 * before_maps / total));
  ASSERT_LT(maps_start, 80) << "the maps' share is too small for a line per map";
  // Two points per map (sampled, written), the last at the end of the encode stage (writing is left to putting the
  // files in place): at least 2 × kMaps − 2 distinct lines strictly between, where one jump per stage would print at
  // most 3.
  std::set<int> during;
  for (const int p : percents) {
    if (p > maps_start + 1 && p < 99) during.insert(p);
  }
  EXPECT_GE(during.size(), static_cast<std::size_t>(2 * kMaps - 2)) << "maps from " << maps_start << "%:\n" << r.err;
}

// `texwarp run`: the job's progress (weighted by the same predicted stage seconds) after startup's share, monotone,
// 100 % once.
TEST_F(LatencyCliTest, RunProgressFollowsTheJobsStages) {
  write("job.json", R"({"warp": {"tolerance_px": 0.01, "features": [
      {"source": [20, 20], "target": [24, 18]}, {"source": [70, 24], "target": [68, 30]},
      {"source": [40, 50], "target": [44, 46]}]}, "image": {"path": ")" +
                        path("in.png") + R"("}})");
  const CliRun r = run("run " + path("job.json") + " --out " + path("job-out") + " --timings=json");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<int> percents = progress_percents(r.err);
  ASSERT_GE(percents.size(), 3u) << r.err;
  EXPECT_TRUE(std::is_sorted(percents.begin(), percents.end())) << r.err;
  EXPECT_EQ(std::count(percents.begin(), percents.end(), 100), 1) << r.err;
  EXPECT_EQ(percents.back(), 100);
  // The job's stages move it between the first line (startup's share) and the end.
  EXPECT_GT(std::count_if(percents.begin(), percents.end(), [&](int p) { return p > percents.front() && p < 100; }), 1)
      << r.err;
}

// The other long-running commands' --progress, from the same clock: monotone, 100 % once and last, the first line
// startup's share of the default workload's prediction, a line where the stages up to `known_after` (the one in
// which the command learns its work) end in this work's prediction, and lines between that and 100 %.
// `startup`: the command's measured startup seconds (its --timings=json).
void expect_weighted_progress(const CliRun& r, double startup_s, const std::vector<proto::LatencyStage>& order,
                              const runner::StageWorkload& work, proto::LatencyStage known_after) {
  const std::vector<int> percents = progress_percents(r.err);
  ASSERT_GE(percents.size(), 3u) << r.err;
  EXPECT_TRUE(std::is_sorted(percents.begin(), percents.end())) << r.err;
  EXPECT_EQ(std::count(percents.begin(), percents.end(), 100), 1) << r.err;
  EXPECT_EQ(percents.back(), 100) << r.err;
  const double startup = std::max(startup_s, 1e-3);
  using proto::LatencyStage;
  // The shares of startup and of the stages up to `through`, of the predicted whole.
  auto share = [&](const runner::StageWorkload& w, LatencyStage through) {
    double total = 0.0;
    double until = 0.0;
    bool passed = false;
    for (const LatencyStage s : order) {
      const double seconds = s == LatencyStage::kStartup ? startup : runner::predicted_seconds(s, w);
      total += seconds;
      if (!passed) until += seconds;
      passed = passed || s == through;
    }
    return until / total;
  };
  EXPECT_NEAR(percents.front(), std::floor(100.0 * share(runner::StageWorkload{}, LatencyStage::kStartup)), 1.0)
      << r.err;
  const int known = static_cast<int>(std::floor(100.0 * share(work, known_after)));
  // Where this work's share up to `known_after` is no larger than the first line (a small work after a slow start,
  // as on a loaded machine), a line there says nothing the first line does not.
  if (known <= percents.front() + 1) return;
  EXPECT_TRUE(std::any_of(percents.begin(), percents.end(), [&](int p) { return std::abs(p - known) <= 1; }))
      << "no line at " << known << "%:\n"
      << r.err;
  EXPECT_TRUE(std::any_of(percents.begin(), percents.end(), [&](int p) { return p > known + 1 && p < 100; })) << r.err;
}

// map-mesh with a warped texture: plan, decode, device, mapping, the texture's pathlines, sampling, encode, write.
TEST_F(LatencyCliTest, MapMeshProgressIsWeightedByPredictedStageSeconds) {
  const std::string examples = std::string(TEXWARP_SOURCE_DIR) + "/examples/";
  const CliRun r = run("map-mesh --backend cpu --mesh " + examples + "mesh/spot.obj --texture " + examples +
                       "astronaut.png --features " + examples + "mesh/spot_head_features.json --region " + examples +
                       "mesh/spot_head_region.json --width 96 --height 64 --out-texture " + path("w.png") +
                       " --out-obj " + path("w.obj") + " --progress --timings=json");
  ASSERT_EQ(r.code, 0) << r.err;
  using proto::LatencyStage;
  ImageHeader texture;
  texture.width = 512;
  texture.height = 512;
  expect_weighted_progress(r, startup_of(r),
                           {LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup,
                            LatencyStage::kMapping, LatencyStage::kPathlines, LatencyStage::kDecode,
                            LatencyStage::kSampling, LatencyStage::kEncode, LatencyStage::kWrite},
                           runner::image_workload(texture, 96, 64, 12, false), LatencyStage::kPlan);
  EXPECT_TRUE(fs::exists(path("w.png")) && fs::exists(path("w.obj")));
  // Without a warped texture its stages are not counted: still monotone, 100 % once, at the end.
  const CliRun mesh_only =
      run("map-mesh --backend cpu --mesh " + examples + "mesh/spot.obj --texture " + examples +
          "astronaut.png --features " + examples + "mesh/spot_head_features.json --region " + examples +
          "mesh/spot_head_region.json --out-obj " + path("m.obj") + " --progress --timings=json");
  ASSERT_EQ(mesh_only.code, 0) << mesh_only.err;
  expect_weighted_progress(mesh_only, startup_of(mesh_only),
                           {LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup,
                            LatencyStage::kMapping, LatencyStage::kWrite},
                           runner::image_workload(texture, 0, 0, 12, false), LatencyStage::kPlan);
}

// check: plan, device, verify (residuals, gradients), then the Jacobian grid's pathlines; the grid is the work.
TEST_F(LatencyCliTest, CheckProgressIsWeightedByPredictedStageSeconds) {
  const CliRun r = run("check --backend cpu --features " + path("moved.json") +
                       " --width 96 --height 64 --grid-step 1 "
                       "--progress --timings=json");
  ASSERT_EQ(r.code, 0) << r.err;
  runner::StageWorkload grid;
  grid.input_pixels = 0.0;
  grid.output_pixels = 96.0 * 64.0;
  grid.features = 3;
  grid.exact = true;
  grid.jacobian_grid = true;
  using proto::LatencyStage;
  expect_weighted_progress(r, startup_of(r),
                           {LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup,
                            LatencyStage::kVerify, LatencyStage::kPathlines},
                           grid, LatencyStage::kPlan);  // the grid is known once the features are
}

// map: plan (features and points), device, the points' pathlines, writing the JSON.
TEST_F(LatencyCliTest, MapProgressIsWeightedByPredictedStageSeconds) {
  std::string points = "[";
  for (int i = 0; i < 4000; ++i)
    points += (i ? "," : "") + std::string("[") + std::to_string(i % 96) + ", " + std::to_string(i / 96 % 64) + "]";
  write("points.json", points + "]");
  const CliRun r = run("map --backend cpu --features " + path("moved.json") + " --points " + path("points.json") +
                       " --progress --timings=json");
  ASSERT_EQ(r.code, 0) << r.err;
  runner::StageWorkload work;
  work.input_pixels = 0.0;
  work.output_pixels = 4000.0;
  work.features = 3;
  work.exact = true;
  using proto::LatencyStage;
  expect_weighted_progress(r, startup_of(r),
                           {LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup,
                            LatencyStage::kPathlines, LatencyStage::kWrite},
                           work, LatencyStage::kPlan);
}

// The compiled files in a PoCL cache folder (program bitcode, and machine code per kernel and launch shape), by
// path relative to it; `last_accessed` stamps and temporary files are not compiles.
std::set<std::string> compiled_files(const fs::path& cache) {
  std::set<std::string> files;
  if (!fs::is_directory(cache)) return files;
  for (const auto& e : fs::recursive_directory_iterator(cache)) {
    if (e.is_regular_file() && (e.path().extension() == ".so" || e.path().filename() == "program.bc")) {
      files.insert(fs::relative(e.path(), cache).string());
    }
  }
  return files;
}

// "(V variants launched, F files compiled)" of `texwarp warm`.
std::array<int, 2> warm_counts(const std::string& err) {
  std::smatch m;
  const std::regex counts(R"(\((\d+) variants launched, (\d+) files compiled\))");
  if (!std::regex_search(err, m, counts)) {
    ADD_FAILURE() << err;
    return {-1, -1};
  }
  return {std::stoi(m[1]), std::stoi(m[2])};
}

// warm: startup, then device set-up alone, whose progress moves as the variants' programs are built: into a fresh
// cache folder (every program compiled, each well over the 0.1 s between looks), a line at (2k − 1) / 2V of device
// set-up's share when the k-th of V = 4 programs is built, monotone, 100 % once and last; --timings names both.
TEST_F(LatencyCliTest, WarmProgressFollowsTheProgramsBuilt) {
  const std::string env = "env -u POCL_CACHE_DIR TEXWARP_CACHE_DIR=" + path("cache") + " ";
  const CliRun r = run("warm --progress --timings=json", env);
  ASSERT_EQ(r.code, 0) << r.err;
  using proto::LatencyStage;
  expect_weighted_progress(r, startup_of(r), {LatencyStage::kStartup, LatencyStage::kDeviceSetup},
                           runner::StageWorkload{}, LatencyStage::kStartup);
  const nlohmann::json timings = timings_of(r.err);
  EXPECT_TRUE(timings["stages"].contains("startup") && timings["stages"].contains("device_setup")) << r.err;
  EXPECT_EQ(timings["stages"].size(), 2u) << r.err;
  const auto [variants, compiled] = warm_counts(r.err);
  ASSERT_EQ(variants, 4) << r.err;  // PoCL's CPU device has fp64
  ASSERT_GT(compiled, 0) << r.err;
  // Device set-up's share, as the clock weighs it: startup measured, device set-up predicted.
  const double startup = std::max(startup_of(r), 1e-3);
  const double device = runner::predicted_seconds(LatencyStage::kDeviceSetup, runner::StageWorkload{});
  const double from = startup / (startup + device);
  const std::vector<int> percents = progress_percents(r.err);
  std::set<int> levels;  // the builds' levels the lines reached
  for (int k = 1; k <= variants; ++k) {
    const double at = from + (1.0 - from) * (2.0 * k - 1.0) / (2.0 * variants);
    const int percent = static_cast<int>(std::floor(100.0 * at));
    if (std::find(percents.begin(), percents.end(), percent) != percents.end()) levels.insert(percent);
  }
  EXPECT_EQ(levels.size(), static_cast<std::size_t>(variants)) << r.err;
  // Nothing else between the first line and device set-up's end (99 % until the command is done): the builds'.
  for (const int p : percents) {
    EXPECT_TRUE(p == percents.front() || p >= 99 || levels.count(p) == 1) << p << "%\n" << r.err;
  }
}

// Warm means warm: after `texwarp warm` into a fresh cache folder, the warps and checks of new processes find
// everything the driver needs there (no file is added to its cache) and build their programs from the binaries
// warm kept in programs/, and the driver's cache is inside the folder. Other commands keep no binaries.
TEST_F(LatencyCliTest, AfterWarmANewProcessCompilesNothing) {
  // The user sets no POCL_CACHE_DIR: texwarp puts PoCL's cache in its own folder.
  const std::string env = "env -u POCL_CACHE_DIR TEXWARP_CACHE_DIR=" + path("cache") + " ";
  const fs::path pocl = dir_ / "cache" / "pocl";
  const CliRun warm = run("warm", env);
  ASSERT_EQ(warm.code, 0) << warm.err;
  EXPECT_NE(warm.err.find("driver's cache " + pocl.string()), std::string::npos) << warm.err;
  // Compiling everything from scratch, quietly: the one line is texwarp's own.
  EXPECT_EQ(std::count(warm.err.begin(), warm.err.end(), '\n'), 1) << warm.err;
  const auto [variants, compiled] = warm_counts(warm.err);
  EXPECT_GE(variants, 2) << warm.err;  // float with and without the Jacobian, at least
  const std::set<std::string> warmed = compiled_files(pocl);
  EXPECT_EQ(static_cast<int>(warmed.size()), compiled) << warm.err;
  // Each variant's built program, which the processes below build from (their launches then find the machine
  // code compiled for the program that the binary holds).
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_ / "cache" / "programs"), fs::directory_iterator()), variants);
  // Each variant's bitcode and the machine code of the launch shape runs use.
  EXPECT_GE(static_cast<int>(warmed.size()), 2 * variants) << warm.err;

  const std::string warp = "warp --features " + path("moved.json") + " --in " + path("in.png") + " --out ";
  for (const std::string& args : {warp + path("lattice.png"), warp + path("exact.png") + " --exact",
                                  "check --features " + path("moved.json") + " --width 96 --height 64"}) {
    const CliRun r = run(args, env);
    ASSERT_EQ(r.code, 0) << args << "\n" << r.err;
    EXPECT_EQ(compiled_files(pocl), warmed) << args << " compiled kernels after warm";
  }
  EXPECT_EQ(warm_counts(run("warm", env).err), (std::array<int, 2>{variants, 0}));

  // Without HOME, XDG_CACHE_HOME and TEXWARP_CACHE_DIR the folder is <TMPDIR>/texwarp-cache-<uid>, only when it is
  // this user's own (then kept to the user: 0700): one that another user made first, open to all, is not used (the
  // driver would load machine code from it). The driver's cache here is the warm one: nothing to compile.
  const std::string folder = "texwarp-cache-" + std::to_string(::getuid());
  const auto fallback = [&](const std::string& tmp) {
    return run("warm", "env -u HOME -u XDG_CACHE_HOME -u TEXWARP_CACHE_DIR POCL_CACHE_DIR=" + pocl.string() +
                           " TMPDIR=" + path(tmp) + " ");
  };
  fs::create_directories(dir_ / "own" / folder);
  fs::permissions(dir_ / "own" / folder, fs::perms::all);
  const CliRun own = fallback("own");
  ASSERT_EQ(own.code, 0) << own.err;
  EXPECT_EQ(fs::status(dir_ / "own" / folder).permissions() & fs::perms::all, fs::perms::owner_all);
  EXPECT_TRUE(fs::exists(dir_ / "own" / folder / "programs")) << own.err;
  fs::create_directories(dir_ / "squatted" / folder);
  fs::permissions(dir_ / "squatted" / folder, fs::perms::all);
  if (::chown((dir_ / "squatted" / folder).c_str(), 65534, 65534) != 0) {
    GTEST_SKIP() << "cannot give a folder to another user here (not root): the squatted case is not run";
  }
  const CliRun squatted = fallback("squatted");
  ASSERT_EQ(squatted.code, 0) << squatted.err;
  EXPECT_TRUE(fs::is_empty(dir_ / "squatted" / folder)) << squatted.err;

  // The count is real: the same warp in a fresh folder, without warm, compiles into it.
  const CliRun cold = run(warp + path("cold.png"), "env -u POCL_CACHE_DIR TEXWARP_CACHE_DIR=" + path("cold") + " ");
  ASSERT_EQ(cold.code, 0) << cold.err;
  EXPECT_GE(compiled_files(dir_ / "cold" / "pocl").size(), 2u);
  EXPECT_FALSE(fs::exists(dir_ / "cold" / "programs"));
}

}  // namespace
}  // namespace texwarp
