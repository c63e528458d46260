// Tests of the `texwarp` command line as pipeline scripts use it: the documented forms, their outputs, exit
// codes (0 ok, 2 invalid input, 1 other failure) and messages naming what is wrong.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "test_folder.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/proto/job_report_codec.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

struct CliRun {
  int code = -1;
  std::string out;
  std::string err;
};

// An OpenColorIO config (profile version 1) whose scene-linear role is its space "lin", with `spaces` (YAML list
// items) after it.
std::string ocio_config(const std::string& spaces) {
  return R"(ocio_profile_version: 1
search_path: ""
strictparsing: true
roles:
  default: lin
  scene_linear: lin
  reference: lin
colorspaces:
  - !<ColorSpace>
    name: lin
    bitdepth: 32f
)" + spaces;
}

class CliTest : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(path(name)) << text;
    return path(name);
  }

  static std::string slurp(const std::string& file) {
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

  // `shell_prefix`: shell commands run first in the same shell (e.g. "ulimit -v N; ").
  CliRun run(const std::string& args, const std::string& shell_prefix = "") const {
    const std::string out = path("stdout.txt");
    const std::string err = path("stderr.txt");
    const std::string cmd = shell_prefix + std::string(TEXWARP_CLI) + " " + args + " >" + out + " 2>" + err;
    const int status = std::system(cmd.c_str());
    CliRun r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }

  texwarp::testing::TestFolder dir_{"cli"};
};

constexpr const char* kFeatures = R"({"alpha": 2.0, "prealign": "similarity", "tolerance_px": 0.001, "features": [
  {"id": "a", "source": [20, 20], "target": [26.5, 18.5]},
  {"id": "b", "source": [80, 25], "target": [78.5, 33.5]},
  {"id": "c", "source": [40, 70], "target": [45.5, 66.5]},
  {"id": "g", "source": [60, 50], "target": [57.5, 52.5],
   "source_frame": {"angle_deg": 0, "scale": 1}, "target_frame": {"angle_deg": 20, "scale": 1.2}}]})";

TEST_F(CliTest, MapPrintsTargetsForSourcesAndBack) {
  const std::string f = write("f.json", kFeatures);
  const std::string p = write("p.json", "[[20, 20], [80, 25], [40, 70], [60, 50], [10, 90]]");
  const CliRun fwd = run("map --features " + f + " --points " + p + " --backend cpu");
  ASSERT_EQ(fwd.code, 0) << fwd.err;
  const auto out = nlohmann::json::parse(fwd.out);
  ASSERT_EQ(out.size(), 5u);
  const double expected[4][2] = {{26.5, 18.5}, {78.5, 33.5}, {45.5, 66.5}, {57.5, 52.5}};
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(out[i][0].get<double>(), expected[i][0], 1e-6);
    EXPECT_NEAR(out[i][1].get<double>(), expected[i][1], 1e-6);
  }
  // The inverse of the printed points gives the inputs back.
  const std::string q = write("q.json", out.dump());
  const CliRun inv = run("map --inverse --features " + f + " --points " + q + " --backend cpu");
  ASSERT_EQ(inv.code, 0) << inv.err;
  const auto back = nlohmann::json::parse(inv.out);
  EXPECT_NEAR(back[4][0].get<double>(), 10.0, 1e-3);
  EXPECT_NEAR(back[4][1].get<double>(), 90.0, 1e-3);
}

TEST_F(CliTest, WarpLandsEveryFeatureWhereAsked) {
  // A source whose two channels hold the x and y of each pixel centre: the warped image then shows, at each
  // output pixel, which source position it pulled. At a target Q (a pixel centre) that must be the source P.
  Image src(100, 90, 2);
  for (int y = 0; y < 90; ++y) {
    for (int x = 0; x < 100; ++x) {
      src.pixel(x, y)[0] = static_cast<float>(x + 0.5);
      src.pixel(x, y)[1] = static_cast<float>(y + 0.5);
    }
  }
  write_image(path("coords.tif"), src, PixelFormat::kFloat);
  const std::string f = write("f.json", kFeatures);
  // Per-pixel pathlines (--exact) at the file's tolerance 0.001, and the certified lattice at 0.02 px.
  const std::string warp = "warp --features " + f + " --in " + path("coords.tif") + " --out " + path("out.tif") +
                           " --border clamp --backend cpu --certificate " + path("cert.json") + " ";
  for (const auto& [flags, bound] : {std::pair<std::string, double>{"--exact", 2e-3}, {"--tolerance-px 0.02", 0.02}}) {
    const CliRun r = run(warp + flags);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("max constraint residual"), std::string::npos);
    ImageHeader header;
    const Image out = read_image(path("out.tif"), {}, &header);
    EXPECT_EQ(header.format, PixelFormat::kFloat);
    ASSERT_EQ(out.channels, 2);
    const auto spec = nlohmann::json::parse(kFeatures);
    for (const auto& feature : spec["features"]) {
      const int qx = static_cast<int>(feature["target"][0].get<double>());
      const int qy = static_cast<int>(feature["target"][1].get<double>());
      EXPECT_NEAR(out.pixel(qx, qy)[0], feature["source"][0].get<double>(), bound) << feature["id"] << flags;
      EXPECT_NEAR(out.pixel(qx, qy)[1], feature["source"][1].get<double>(), bound) << feature["id"] << flags;
    }
    const auto cert = nlohmann::json::parse(slurp(path("cert.json")));
    for (const char* key : {"max_error_px_estimated", "max_error_px_sampled", "min_jacobian_det", "pathlines"}) {
      EXPECT_TRUE(cert.contains(key)) << key;
    }
    EXPECT_GT(cert["min_jacobian_det"].get<double>(), 0.0);
    EXPECT_LE(cert["max_error_px_sampled"].get<double>(), bound);
  }
}

TEST_F(CliTest, BaselinesFoldWhereTheFieldDoesNot) {
  const std::string f = std::string(TEXWARP_SOURCE_DIR) + "/examples/swirl-features.json";
  int folds[3] = {};
  int k = 0;
  for (const char* method : {"field", "tps", "mls"}) {
    const CliRun r =
        run("check --features " + f + " --width 512 --height 512 --grid-step 16 --backend cpu --method " + method);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["method"], method);
    EXPECT_LE(j["residuals"]["max_px"].get<double>(), 0.05) << method;  // all three interpolate
    folds[k++] = j["jacobian"]["nonpositive"].get<int>();
  }
  EXPECT_EQ(folds[0], 0);
  EXPECT_GT(folds[1], 0);
  EXPECT_GT(folds[2], 0);
}

TEST_F(CliTest, WarpOptionsSizeFormatInterpolation) {
  Image src(32, 24, 3);
  for (std::size_t i = 0; i < src.pixels.size(); ++i) src.pixels[i] = static_cast<float>(i % 7) / 7.0f;
  write_image(path("in.png"), src, PixelFormat::kUint8);
  const std::string f = write(
      "f.json", R"({"features": [{"source": [5, 5], "target": [6, 5]}, {"source": [25, 18], "target": [24, 19]}]})");
  const CliRun r = run("warp --features " + f + " --in " + path("in.png") + " --out " + path("out.png") +
                       " --width 40 --height 30 --interp bicubic --border repeat --format uint16 --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  ImageHeader h = read_image_header(path("out.png"));
  EXPECT_EQ(h.width, 40);
  EXPECT_EQ(h.height, 30);
  EXPECT_EQ(h.channels, 3);  // repeat: no alpha added
  EXPECT_EQ(h.format, PixelFormat::kUint16);
  const CliRun t =
      run("warp --features " + f + " --in " + path("in.png") + " --out " + path("t.png") + " --backend cpu");
  ASSERT_EQ(t.code, 0) << t.err;
  EXPECT_EQ(read_image_header(path("t.png")).channels, 4);  // transparent (default): alpha added
}

TEST_F(CliTest, RolesAreGivenWithTheInputAndSaidInTheSummary) {
  // A flat normal map tilted toward +x, turned 90° by three features on a rotated copy (a closed-form similarity):
  // as a normal map its tilt turns with it (OpenGL: +x becomes −y up the texture, so green rises); as data it
  // keeps its values.
  Image map(64, 64, 3);
  const double n[3] = {0.6, 0.0, 0.8};
  for (int i = 0; i < 64 * 64; ++i) {
    for (int c = 0; c < 3; ++c) map.pixels[3 * i + c] = static_cast<float>(0.5 * (n[c] + 1.0));
  }
  write_image(path("normal.png"), map, PixelFormat::kUint16);
  const std::string f = write("turn.json", R"({"features": [{"source": [10, 10], "target": [54, 10]},
    {"source": [50, 12], "target": [52, 50]}, {"source": [20, 40], "target": [24, 20]}]})");
  CliRun r = run("warp --features " + f + " --in normal=" + path("normal.png") + " --out " + path("n.png") +
                 " --border clamp --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as normal (opengl), footprint filter"));
  const Image turned = read_image(path("n.png"));
  // Image y runs down: the tilt (0.6, 0) turned by +90° is (0, 0.6) in image coordinates, green = −y → 0.2.
  EXPECT_NEAR(turned.pixel(32, 32)[0], 0.5, 2e-3);
  EXPECT_NEAR(turned.pixel(32, 32)[1], 0.2, 2e-3);
  EXPECT_NEAR(turned.pixel(32, 32)[2], 0.9, 2e-3);
  r = run("warp --features " + f + " --in data=" + path("normal.png") + " --out " + path("d.png") +
          " --border clamp --backend cpu --filter point");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as data, point filter"));
  EXPECT_NEAR(read_image(path("d.png")).pixel(32, 32)[0], 0.8, 2e-3);
  // The file's default: an untagged 16-bit PNG is sRGB colour.
  r = run("warp --features " + f + " --in " + path("normal.png") + " --out " + path("c.png") + " --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as color (sRGB)"));
  // Bad roles and colour spaces: exit 2 naming the flag and the valid names, nothing written.
  r = run("warp --features " + f + " --in albedo=" + path("normal.png") + " --out " + path("x.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, ::testing::HasSubstr(R"(--in: unknown role "albedo")"));
  EXPECT_THAT(r.err, ::testing::HasSubstr(R"("color", "data" or "normal")"));
  r = run("warp --features " + f + " --in " + path("normal.png") + " --colorspace ACEScg --out " + path("x.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err,
              ::testing::HasSubstr(R"(--colorspace: unknown colour space "ACEScg": expected "sRGB" or "linear")"));
  EXPECT_FALSE(fs::exists(path("x.png")));
}

TEST_F(CliTest, ColourSpacesOfAnOpenColorIoConfigFilterInItsSceneLinear) {
  // A config whose "gamma22" is a pure 2.2 power: a 1 px checker minified 2× is light 0.5, 0.5^(1/2.2) = 186/255
  // (sRGB's 188; the codes' mean 128).
  const std::string config = write("gamma.ocio", ocio_config(R"(  - !<ColorSpace>
    name: gamma22
    bitdepth: 32f
    to_reference: !<ExponentTransform> {value: [2.2, 2.2, 2.2, 1]}
)"));
  Image checker(64, 64, 3);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      for (int c = 0; c < 3; ++c) checker.pixel(x, y)[c] = static_cast<float>((x + y) % 2);
    }
  }
  write_image(path("checker.png"), checker, PixelFormat::kUint8);
  const std::string f = write("half.json", R"({"features": [{"source": [10, 20], "target": [5, 10]},
    {"source": [50, 8], "target": [25, 4]}, {"source": [20, 60], "target": [10, 30]}]})");
  const std::string ocio = "OCIO=" + config + " ";
  CliRun r = run("warp --features " + f + " --in " + path("checker.png") + " --colorspace gamma22 --width 32 " +
                     "--height 32 --border clamp --out " + path("g.png"),
                 ocio);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as color (gamma22)"));
  const Image g = read_image(path("g.png"));
  EXPECT_NEAR(g.pixel(16, 16)[0] * 255.0f, 186.0f, 0.01f);
  // A texture records its space, and the config's name is the space it is read in again: no flag needed. Without
  // the config, a name that OpenImageIO's built-in config does not know ("lin") leaves the file's default (sRGB for
  // 8 bits).
  const std::string warp_in = "warp --features " + f + " --in ";
  for (const std::string space : {"gamma22", "lin"}) {
    const std::string tx = path(space + ".tx");
    std::string written = warp_in;
    written.append(path("checker.png")).append(" --colorspace ").append(space).append(" --out ").append(tx);
    r = run(written, ocio);
    ASSERT_EQ(r.code, 0) << r.err;
    std::string read_back = warp_in;
    read_back.append(tx).append(" --out ").append(path("again.png"));
    r = run(read_back, ocio);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.err, ::testing::HasSubstr(std::string("sampled as color (").append(space).append(")")));
  }
  r = run("warp --features " + f + " --in " + path("lin.tx") + " --out " + path("again.png"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as color (sRGB)"));
  r = run("warp --features " + f + " --in " + path("checker.png") + " --colorspace ACEScg --out " + path("x.png"),
          ocio);
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, ::testing::HasSubstr("in the OpenColorIO config $OCIO names; its spaces: lin, gamma22"));
}

TEST_F(CliTest, AFileDeclaringASpaceTheConfigMarksAsDataIsDataWhateverItsName) {
  // "utility_data" is none of the built-in data names (Raw, Non-Color, Utility - Raw): only the config's isdata says
  // it holds values. A studio config names such spaces as it likes.
  const std::string config = write("data.ocio", ocio_config(R"(  - !<ColorSpace>
    name: utility_data
    bitdepth: 32f
    isdata: true
)"));
  const std::string ocio = "OCIO=" + config + " ";
  Image ramp(32, 32, 3);
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) {
      for (int c = 0; c < 3; ++c) ramp.pixel(x, y)[c] = static_cast<float>(x) / 31.0f;
    }
  }
  write_image(path("ramp.png"), ramp, PixelFormat::kUint8);
  const std::string f = write("f.json", R"({"features": [{"source": [10, 20], "target": [11, 20]},
    {"source": [20, 8], "target": [21, 8]}, {"source": [16, 28], "target": [17, 28]}]})");
  // Named on the command line, the space makes the image colour (as documented): the texture records it.
  CliRun r = run("warp --features " + f + " --in " + path("ramp.png") + " --colorspace utility_data --out " +
                     path("declared.tx"),
                 ocio);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as color (utility_data)"));
  // Read back under the config, the file's declared space is data: sampled as data, and its own texture records
  // "Raw", which reads as data with no config at all.
  r = run("warp --features " + f + " --in " + path("declared.tx") + " --out " + path("again.tx"), ocio);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as data"));
  r = run("warp --features " + f + " --in " + path("again.tx") + " --out " + path("third.png"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as data"));
  // Without the config, "utility_data" is a name nothing knows: the 8-bit file's default, sRGB colour.
  r = run("warp --features " + f + " --in " + path("declared.tx") + " --out " + path("plain.png"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, ::testing::HasSubstr("sampled as color (sRGB)"));
}

TEST_F(CliTest, CheckReportsJacobianResidualsAndGradients) {
  const std::string f = write("f.json", kFeatures);
  const CliRun r = run("check --features " + f + " --width 100 --height 90 --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(j["valid"].get<bool>());
  EXPECT_EQ(j["features"]["total"], 4);
  EXPECT_EQ(j["features"]["gradient"], 1);
  EXPECT_EQ(j["jacobian"]["nonpositive"], 0);
  EXPECT_GT(j["jacobian"]["min_det"].get<double>(), 0.0);
  EXPECT_EQ(j["jacobian"]["samples"], 100 * 90);
  EXPECT_LE(j["residuals"]["max_px"].get<double>(), 1e-6);
  EXPECT_NEAR(j["gradient_features"][0]["measured_scale"].get<double>(), 1.2, 1e-5);
  EXPECT_NEAR(j["gradient_features"][0]["angle_error_deg"].get<double>(), 0.0, 1e-3);
  EXPECT_GT(j["closest_approach"]["distance_px"].get<double>(), 0.5);  // the collision threshold
  EXPECT_EQ(j["closest_approach"]["features"].size(), 2u);
  EXPECT_FALSE(j["trajectory"].contains("energy"));  // straight lines: no energy to lower
  // Two features that swap: planned trajectories, whose pair energy the planner lowered.
  const std::string swap = write("swap.json", R"({"prealign": "none", "features": [
    {"source": [20, 40], "target": [70, 41]}, {"source": [70, 40], "target": [20, 41]},
    {"source": [45, 10], "target": [45, 10]}, {"source": [45, 75], "target": [45, 75]}]})");
  const CliRun planned = run("check --features " + swap + " --width 100 --height 90 --backend cpu");
  ASSERT_EQ(planned.code, 0) << planned.err;
  const auto t = nlohmann::json::parse(planned.out)["trajectory"];
  EXPECT_NE(t["method"], "straight");
  ASSERT_TRUE(t.contains("energy") && t.contains("energy_before")) << t.dump();
  EXPECT_LT(t["energy"].get<double>(), t["energy_before"].get<double>());
  EXPECT_GT(t["energy"].get<double>(), 0.0);
}

// A grid no run could finish is refused before any work, naming the flag to change (it failed in a vector's
// reserve, exit 1).
TEST_F(CliTest, CheckRefusesAJacobianGridTooLargeToRun) {
  const std::string f = write("f.json", kFeatures);
  const CliRun huge =
      run("check --features " + f + " --width 2000000000 --height 2000000000 --grid-step 1 --backend cpu");
  EXPECT_EQ(huge.code, 2) << huge.err;
  EXPECT_NE(huge.err.find("--grid-step"), std::string::npos) << huge.err;
  EXPECT_NE(huge.err.find("use a larger --grid-step"), std::string::npos) << huge.err;
}

TEST_F(CliTest, CheckReportIsTheTypedReportsEncoding) {
  const std::string f = write("f.json", kFeatures);
  for (const char* method : {"field", "mls"}) {
    const CliRun r = run("check --features " + f + " --width 100 --height 90 --backend cpu --method " + method);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const proto::CheckReport report = proto::decode_check_report(j);
    EXPECT_TRUE(report.valid());
    EXPECT_EQ(report.method, method);
    EXPECT_EQ(report.features.gradient, 1u);
    EXPECT_EQ(report.jacobian.output_size, (std::array<int, 2>{100, 90}));
    EXPECT_EQ(report.jacobian.map, method == std::string("field") ? proto::JacobianEstimate::kVariationalEquation
                                                                  : proto::JacobianEstimate::kCentralDifferences);
    EXPECT_EQ(proto::encode_check_report(report), j);
  }
  const std::string bad = write("dup.json", R"({"features": [{"source": [1, 2], "target": [3, 4]},
                                                   {"source": [1, 2], "target": [5, 4]}]})");
  const CliRun r = run("check --features " + bad + " --backend cpu");
  EXPECT_EQ(r.code, 2);
  const auto j = nlohmann::json::parse(r.out);
  const proto::CheckReport report = proto::decode_check_report(j);
  ASSERT_FALSE(report.valid());
  EXPECT_NE(report.failure->where.find("$.features[1]"), std::string::npos) << report.failure->where;
  EXPECT_EQ(proto::encode_check_report(report), j);
}

TEST_F(CliTest, InvalidInputExitsTwoAndNamesThePlace) {
  const std::string p = write("p.json", "[[1, 2]]");
  struct Case {
    std::string file;
    std::string expected;
  };
  const Case cases[] = {
      {R"({"features": [{"source": [1, 2], "target": [3, 4], "colour": 1}]})", "$.features[0].colour: unknown key"},
      {R"({"alpha": -1, "features": []})", "$.alpha: alpha must be in (0, 8]"},
      {R"({"features": [{"source": [1, 2]}]})", "$.features[0].target: required key is missing"},
      {R"({"features": [{"source": [1, 2], "target": [3, 4]}, {"source": [1, 2], "target": [5, 4]}]})",
       "$.features[1]: duplicate source position (1, 2)"},
      {R"({"prealign": "none", "features": [{"id": "l", "source": [0, 0], "target": [10, 0]},
          {"id": "r", "source": [0.3, 0], "target": [0, 10]}]})",
       R"(features[0] ("l") and features[1] ("r") come within 0.3 px of each other at t = 0)"},
      {R"({"features": [)", "not valid JSON"},
  };
  const std::string map = "map --points " + p + " --backend cpu --features ";
  int k = 0;
  for (const Case& c : cases) {
    const std::string f = write("bad" + std::to_string(k++) + ".json", c.file);
    const CliRun r = run(map + f);
    EXPECT_EQ(r.code, 2) << c.file;
    EXPECT_TRUE(r.out.empty());
    EXPECT_NE(r.err.find(f), std::string::npos) << r.err;  // the file is named
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
  }
  // check reports the same as JSON on stdout, still exiting 2.
  const CliRun chk = run("check --features " + path("bad4.json") + " --backend cpu");
  EXPECT_EQ(chk.code, 2);
  const auto j = nlohmann::json::parse(chk.out);
  EXPECT_FALSE(j["valid"].get<bool>());
  EXPECT_NE(j["error"].get<std::string>().find("come within"), std::string::npos);
}

// OpenImageIO (and the ~260 libraries it brings) is not linked into texwarp: PNG goes through libpng, and every
// other format through the image module, loaded on first need. Without the module, a PNG warp still runs, and a
// TIFF is an error that names the file, the format and where the module was looked for.
TEST_F(CliTest, OpenImageIoIsLoadedOnlyForFormatsOtherThanPng) {
  const std::string needed = path("needed.txt");
  ASSERT_EQ(std::system(("readelf -d " + std::string(TEXWARP_CLI) + " > " + needed).c_str()), 0);
  const std::string dynamic = slurp(needed);
  EXPECT_NE(dynamic.find("(NEEDED)"), std::string::npos) << dynamic;
  EXPECT_EQ(dynamic.find("OpenImageIO"), std::string::npos) << dynamic;

  Image src(24, 16, 3);
  for (std::size_t i = 0; i < src.pixels.size(); ++i) src.pixels[i] = static_cast<float>(i % 256) / 255.0f;
  write_image(path("a.png"), src, PixelFormat::kUint8);
  write_image(path("a.tif"), src, PixelFormat::kUint8);
  const std::string f = write("f.json", R"({"features": []})");
  fs::create_directories(path("empty"));
  const std::string no_module = "TEXWARP_MODULE_DIR=" + path("empty") + " ";
  CliRun r = run("warp --features " + f + " --in " + path("a.png") + " --out " + path("o.png"), no_module);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(read_image(path("o.png")).width, 24);
  r = run("warp --features " + f + " --in " + path("a.tif") + " --out " + path("o.png"), no_module);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find(path("a.tif") + ": reading .tif needs the OpenImageIO module at " + path("empty") +
                       "/libtexwarp_image_oiio.so: no such file"),
            std::string::npos)
      << r.err;
  r = run("warp --features " + f + " --in " + path("a.png") + " --out " + path("o.exr"), no_module);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("writing .exr needs the OpenImageIO module at "), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("o.exr")));
  // A module that is not one: what dlopen said.
  fs::create_directories(path("broken"));
  write("broken/libtexwarp_image_oiio.so", "not a shared object");
  r = run("warp --features " + f + " --in " + path("a.tif") + " --out " + path("o.png"),
          "TEXWARP_MODULE_DIR=" + path("broken") + " ");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(
      r.err.find("reading .tif needs the OpenImageIO module at " + path("broken") + "/libtexwarp_image_oiio.so: "),
      std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("no such file"), std::string::npos) << r.err;
  // With the module where the build put it, the TIFF reads.
  r = run("warp --features " + f + " --in " + path("a.tif") + " --out " + path("o.png"));
  EXPECT_EQ(r.code, 0) << r.err;
  // Started by its bare name through PATH from a folder that holds a folder named `texwarp` and a junk module:
  // the module is looked for beside the executable itself (/proc/self/exe), never in the current folder.
  fs::create_directories(path("cwd/texwarp"));
  write("cwd/libtexwarp_image_oiio.so", "not a shared object");
  const fs::path cli(TEXWARP_CLI);
  const std::string cmd = "cd " + path("cwd") + " && PATH=" + cli.parent_path().string() + ":$PATH " +
                          cli.filename().string() + " warp --features " + f + " --in " + path("a.tif") + " --out " +
                          path("o2.png") + " 2>" + path("cwd-err.txt");
  EXPECT_EQ(std::system(cmd.c_str()), 0) << slurp(path("cwd-err.txt"));
  EXPECT_EQ(read_image(path("o2.png")).width, 24);
}

// OpenBLAS (under CHOLMOD) starts a pool of spinning threads when it loads; texwarp stops it and runs BLAS on one
// thread unless the user set a thread count (core/mesh/src/blas_thread_default.cpp). Seen from outside: the threads
// of a `texwarp wait` blocked on a server that never answers, against the same command with OpenBLAS's variables set.
TEST_F(CliTest, OpenBlasStartsNoThreadPoolUnlessItsThreadCountIsSet) {
  if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one core: OpenBLAS starts no pool";
  const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
  ASSERT_GE(listener, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof(addr);
  ASSERT_EQ(::bind(listener, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0);
  ASSERT_EQ(::listen(listener, 16), 0);
  ASSERT_EQ(::getsockname(listener, reinterpret_cast<sockaddr*>(&addr), &len), 0);
  const std::string server = "http://127.0.0.1:" + std::to_string(ntohs(addr.sin_port));
  // The threads of the command once it has connected (its constructors long done), then it is killed.
  const auto threads_with = [&](const std::string& variables) {
    const std::string pid_file = path("pid.txt");
    const std::string cmd = "env -u OPENBLAS_NUM_THREADS -u GOTO_NUM_THREADS -u OMP_NUM_THREADS " + variables + " " +
                            std::string(TEXWARP_CLI) + " wait j --quiet --timeout 30 --server " + server +
                            " >/dev/null 2>&1 & echo $! >" + pid_file;
    EXPECT_EQ(std::system(cmd.c_str()), 0);
    const int pid = std::stoi(slurp(pid_file));
    pollfd ready{listener, POLLIN, 0};
    if (::poll(&ready, 1, 20000) != 1) {
      ::kill(pid, SIGKILL);
      ADD_FAILURE() << "the command never connected (" << variables << ")";
      return -1;
    }
    const int connection = ::accept(listener, nullptr, nullptr);
    int count = 0;
    for ([[maybe_unused]] const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task")) ++count;
    ::kill(pid, SIGKILL);  // not this process's child (the shell's): init reaps it
    if (connection >= 0) ::close(connection);
    return count;
  };
  const int one = threads_with("OPENBLAS_NUM_THREADS=1");
  const int pool = threads_with("OPENBLAS_NUM_THREADS=2");
  if (pool <= one) GTEST_SKIP() << "the BLAS under CHOLMOD starts no thread pool here (not OpenBLAS's pthread build)";
  EXPECT_EQ(threads_with(""), one);
  EXPECT_EQ(threads_with("OMP_NUM_THREADS=2"), pool);  // the user's choice stands
  ::close(listener);
}

TEST_F(CliTest, MissingFilesAndBadArgumentsExitTwo) {
  const std::string f = write("f.json", kFeatures);
  CliRun r = run("map --features " + path("nope.json") + " --points " + f);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("nope.json: cannot open the file"), std::string::npos) << r.err;
  r = run("warp --features " + f + " --in " + path("nope.png") + " --out " + path("o.png") + " --backend cpu");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("nope.png: no such file"), std::string::npos) << r.err;
  r = run("warp --features " + f + " --in " + f + " --out " + path("o.png") + " --backend cpu");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("cannot read as an image"), std::string::npos) << r.err;
  r = run("warp --features " + f + " --interp nearest --in x --out y");
  EXPECT_EQ(r.code, 2);
  r = run("frobnicate");
  EXPECT_EQ(r.code, 2);
  r = run("map --points " + f);  // --features missing
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(fs::exists(path("o.png")));
}

TEST_F(CliTest, UnknownDeviceExitsTwoAndNamesIt) {
  const std::string f = write("f.json", kFeatures);
  const std::string p = write("p.json", "[[20, 20]]");
  const CliRun r = run("map --features " + f + " --points " + p + " --backend opencl --device no-such-device");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(r.out.empty());
  EXPECT_NE(r.err.find("--device"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no-such-device"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("available:"), std::string::npos) << r.err;  // and the devices there are
}

TEST_F(CliTest, UnwritableOutputFailsWithExitOneAndLeavesNothing) {
  Image src(8, 8, 1);
  write_image(path("in.png"), src, PixelFormat::kUint8);
  const std::string f = write("f.json", R"({"features": []})");
  const CliRun r = run("warp --features " + f + " --in " + path("in.png") + " --out " + path("missing-dir/out.png") +
                       " --backend cpu");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("missing-dir/out.png"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("missing-dir")));
}

TEST_F(CliTest, HelpDocumentsExitCodes) {
  const CliRun r = run("--help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("Exit codes: 0 success, 2 invalid input"), std::string::npos);
  for (const char* cmd : {"map", "warp", "check"}) EXPECT_NE(r.out.find(cmd), std::string::npos);
}

TEST_F(CliTest, WarpBeyondTheMemoryBudgetExitsTwoWithTheNumbers) {
  write_image(path("in.png"), Image(64, 48, 3), PixelFormat::kUint8);
  const std::string f = write(
      "f.json", R"({"features": [{"source": [5, 5], "target": [6, 5]}, {"source": [50, 40], "target": [49, 41]}]})");
  const CliRun r = run("warp --features " + f + " --in " + path("in.png") + " --out " + path("out.png") +
                       " --width 100000 --height 100000 --backend cpu");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(r.err.find("bad_alloc"), std::string::npos) << r.err;
  // 10¹⁰ output pixels: positions alone are 160 GB; the message names the image, the size and the flag.
  EXPECT_NE(r.err.find("in.png (warped to 100000×100000): this job needs about "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("source positions of 100000×100000 output pixels 160 GB"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the memory limit per job is "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("(--max-job-memory-mb)"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out.png")));
  // The budget is the caller's to set: 1 MiB is too little for a 64×48 warp into 400×400 ...
  const CliRun small = run("warp --features " + f + " --in " + path("in.png") + " --out " + path("out.png") +
                           " --width 400 --height 400 --max-job-memory-mb 1 --backend cpu");
  EXPECT_EQ(small.code, 2) << small.err;
  EXPECT_NE(small.err.find("the memory limit per job is 1.0 MB (--max-job-memory-mb)"), std::string::npos) << small.err;
  // ... and enough for 64×48 into 80×60.
  const CliRun fits = run("warp --features " + f + " --in " + path("in.png") + " --out " + path("out.png") +
                          " --width 80 --height 60 --max-job-memory-mb 16 --backend cpu");
  EXPECT_EQ(fits.code, 0) << fits.err;
}

TEST_F(CliTest, OutOfMemoryIsAClearMessageNotBadAlloc) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "sanitizers reserve more address space than this test allows the command";
#endif
  write_image(path("in.png"), Image(64, 48, 3), PixelFormat::kUint8);
  const std::string f = write(
      "f.json", R"({"features": [{"source": [5, 5], "target": [6, 5]}, {"source": [50, 40], "target": [49, 41]}]})");
  // A budget above what the process may have (its address space capped at 1 GB): an allocation fails.
  const CliRun r = run("warp --features " + f + " --in " + path("in.png") + " --out " + path("out.png") +
                           " --width 100000 --height 100000 --max-job-memory-mb 100000000 --backend cpu",
                       "ulimit -v 1000000; ");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("texwarp: error: out of memory while running `texwarp warp`"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("bad_alloc"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out.png")));
}

TEST_F(CliTest, TruncatedInputImageExitsTwoNamingIt) {
  Image src(96, 80, 3);
  std::uint32_t state = 7;
  for (float& v : src.pixels) {
    state = state * 1664525u + 1013904223u;
    v = static_cast<float>(state >> 24) / 255.0f;
  }
  write_image(path("whole.jpg"), src, PixelFormat::kUint8);
  const std::string bytes = slurp(path("whole.jpg"));
  std::ofstream(path("cut.jpg"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  const std::string f = write(
      "f.json", R"({"features": [{"source": [5, 5], "target": [6, 5]}, {"source": [50, 40], "target": [49, 41]}]})");
  const CliRun r =
      run("warp --features " + f + " --in " + path("cut.jpg") + " --out " + path("out.png") + " --backend cpu");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("cut.jpg: is truncated or corrupt: "), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out.png")));
}

}  // namespace
}  // namespace texwarp
