// The pixel format and channels a command says it wrote are the ones the file holds: `texwarp warp`'s summary line,
// `texwarp run`'s report.json and `texwarp map-mesh`'s texture line against the file read back with OpenImageIO, for
// PNG 8 and 16 bits, EXR (no 8 or 16-bit integers: half), TIFF (no half: float), JPEG (no alpha: an RGBA warp holds
// 3 channels) and the formats asked with --format.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "test_folder.hpp"

namespace {

namespace fs = std::filesystem;

struct CliRun {
  int code = -1;
  std::string err;
};

// The name texwarp gives (proto/enum_names) of the sample type OpenImageIO finds in `path`; "?" for another type.
std::string stored_format(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return "cannot open: " + OIIO::geterror();
  switch (in->spec().format.basetype) {
    case OIIO::TypeDesc::UINT8:
      return "uint8";
    case OIIO::TypeDesc::UINT16:
      return "uint16";
    case OIIO::TypeDesc::HALF:
      return "half";
    case OIIO::TypeDesc::FLOAT:
      return "float";
    default:
      return "?" + std::string(in->spec().format.c_str());
  }
}

// The channels OpenImageIO finds in `path`; -1 when it cannot open it.
int stored_channels(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  return in ? in->spec().nchannels : -1;
}

class WrittenFormatTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // RGB inputs written by OpenImageIO itself, 8 and 16 bits.
    for (const auto& [name, type] :
         {std::pair{"in8.png", OIIO::TypeDesc::UINT8}, {"in16.png", OIIO::TypeDesc::UINT16}}) {
      OIIO::ImageSpec spec(48, 32, 3, type);
      std::vector<float> pixels(std::size_t{48} * 32 * 3);
      for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<float>(i * 29 % 97) / 96.0f;
      auto out = OIIO::ImageOutput::create(path(name));
      ASSERT_TRUE(out && out->open(path(name), spec) && out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) &&
                  out->close())
          << OIIO::geterror();
      ASSERT_EQ(stored_format(path(name)), type == OIIO::TypeDesc::UINT8 ? "uint8" : "uint16");
    }
    std::ofstream(path("f.json")) << R"({"features": [{"source": [10, 10], "target": [12, 9]},
      {"source": [36, 22], "target": [35, 24]}]})";
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  CliRun run(const std::string& args) const {
    const std::string err = path("stderr.txt");
    const int status = std::system((std::string(TEXWARP_CLI) + " " + args + " >/dev/null 2>" + err).c_str());
    CliRun r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(err);
    std::stringstream ss;
    ss << in.rdbuf();
    r.err = ss.str();
    return r;
  }

  texwarp::testing::TestFolder dir_{"format"};
};

// Field `field` (1: channels, 2: pixel format) of "wrote FILE (W×H, C channels, FORMAT)" in `err`.
std::string printed_field(const std::string& err, const std::string& file, int field) {
  std::smatch m;
  const std::regex wrote("wrote " + std::regex_replace(file, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") +
                         R"( \(\d+×\d+, (\d+) channels, (\w+)\))");
  return std::regex_search(err, m, wrote) ? m[field].str() : "(no line for " + file + ")";
}
std::string printed_format(const std::string& err, const std::string& file) { return printed_field(err, file, 2); }
std::string printed_channels(const std::string& err, const std::string& file) { return printed_field(err, file, 1); }

struct Case {
  const char* input;
  const char* output;
  const char* format_flag;       // --format, "" for the input's
  const char* stored;            // what the file must hold
  const char* border = "clamp";  // "transparent" adds alpha to the RGB inputs: 4 channels warped
  int channels = 3;              // the channels the file must hold
};

TEST_F(WrittenFormatTest, WarpPrintsThePixelFormatTheFileHolds) {
  const Case cases[] = {
      {"in8.png", "a.png", "", "uint8"},
      {"in16.png", "b.png", "", "uint16"},
      {"in8.png", "c.exr", "", "half"},
      {"in16.png", "d.exr", "", "half"},
      {"in8.png", "e.tif", "", "uint8"},
      {"in16.png", "f.tif", "", "uint16"},
      {"in8.png", "g.tif", "half", "float"},
      {"in8.png", "h.exr", "float", "float"},
      {"in8.png", "i.png", "half", "uint8"},
      {"in8.png", "j.png", "uint16", "uint16"},
      {"in16.png", "k.jpg", "", "uint8"},
      {"in8.png", "l.png", "", "uint8", "transparent", 4},
      {"in8.png", "m.jpg", "", "uint8", "transparent", 3},  // a JPEG drops the alpha warped in
      {"in8.png", "n.exr", "", "half", "transparent", 4},
      {"in8.png", "o.tif", "", "uint8", "transparent", 4},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.input) + " → " + c.output + " " + c.format_flag);
    const std::string format = *c.format_flag ? std::string(" --format ") + c.format_flag : "";
    const CliRun r = run("warp --backend cpu --features " + path("f.json") + " --in " + path(c.input) + " --out " +
                         path(c.output) + " --border " + c.border + format + " --certificate " + path("cert.json"));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(stored_format(path(c.output)), c.stored);
    EXPECT_EQ(printed_format(r.err, path(c.output)), c.stored) << r.err;
    EXPECT_EQ(stored_channels(path(c.output)), c.channels);
    EXPECT_EQ(printed_channels(r.err, path(c.output)), std::to_string(c.channels)) << r.err;
    // The certificate names no pixel format: nothing there to contradict the file.
    std::ifstream cert(path("cert.json"));
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(cert), {}).find("format"), std::string::npos);
  }
}

TEST_F(WrittenFormatTest, RunReportsThePixelFormatTheFileHolds) {
  const Case cases[] = {
      {"in8.png", "png", "", "uint8"},
      {"in16.png", "png", "", "uint16"},
      {"in8.png", "exr", "", "half"},
      {"in8.png", "exr", "uint16", "half"},
      {"in8.png", "tiff", "", "uint8"},
      {"in8.png", "tiff", "half", "float"},
      {"in16.png", "tiff", "float", "float"},
      {"in8.png", "exr", "", "half", "transparent", 4},
      {"in8.png", "png", "", "uint8", "transparent", 4},
  };
  int n = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.input) + " → " + c.output + " " + c.format_flag);
    nlohmann::json job = {
        {"warp", nlohmann::json::parse(std::ifstream(path("f.json")))},
        {"image", {{"path", path(c.input)}}},
        {"output", {{"file_format", c.output}, {"border", c.border}}},
    };
    if (*c.format_flag) job["output"]["pixel_format"] = c.format_flag;
    std::ofstream(path("job.json")) << job.dump();
    const std::string out = path("out" + std::to_string(n++));
    const CliRun r = run("run --quiet " + path("job.json") + " --out " + out);
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json report = nlohmann::json::parse(std::ifstream(out + "/report.json"));
    const std::string file = report.at("output").at("file").get<std::string>();
    EXPECT_EQ(file, std::string("warped.") + c.output);
    const std::string written = (fs::path(out) / file).string();
    EXPECT_EQ(stored_format(written), c.stored);
    EXPECT_EQ(report.at("output").at("pixel_format"), c.stored) << report.dump(2);
    EXPECT_EQ(stored_channels(written), c.channels);
    EXPECT_EQ(report.at("output").at("channels"), c.channels) << report.dump(2);
  }
}

TEST_F(WrittenFormatTest, MapMeshPrintsThePixelFormatOfItsWarpedTexture) {
  const std::string examples = std::string(TEXWARP_SOURCE_DIR) + "/examples/";
  const std::string args = "map-mesh --backend cpu --mesh " + examples + "mesh/spot.obj --texture " + examples +
                           "astronaut.png --features " + examples + "mesh/spot_head_features.json --region " +
                           examples + "mesh/spot_head_region.json --width 64 --height 64 --out-texture ";
  for (const auto& [file, flag, stored] : {std::tuple{"w.exr", "", "half"},
                                           {"w.tif", " --format half", "float"},
                                           {"w.png", " --format uint16", "uint16"},
                                           {"w.jpg", "", "uint8"}}) {
    SCOPED_TRACE(file);
    const CliRun r = run(args + path(file) + flag);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(stored_format(path(file)), stored);
    EXPECT_EQ(printed_format(r.err, path(file)), stored) << r.err;
    EXPECT_EQ(printed_channels(r.err, path(file)), std::to_string(stored_channels(path(file)))) << r.err;
  }
}

}  // namespace
