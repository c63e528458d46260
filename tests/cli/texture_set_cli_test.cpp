// `texwarp warp` on texture sets and UDIM tiles (issue 30): `--in [ROLE=]PATH` repeated with `--out-dir DIR` warps
// every map by one map of the output grid; each output keeps its input's file name and must hold exactly the pixels
// of that map warped alone with `--out`. A <UDIM> path's tiles must equal their canvas, stitched by hand, warped and
// cut again. .tx (and --texture) outputs are tiled, MIP-mapped to 1×1, record the role's colour space and hold the
// warped pixels. Bad sets and tiles exit 2 naming what is wrong, and a set that fails part way writes nothing.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <OpenImageIO/imageio.h>

#include "test_folder.hpp"
#include "texwarp/core/image_io.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

struct CliRun {
  int code = -1;
  std::string err;
};

class TextureSetCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Four maps of one asset, 96²: sRGB colour (8-bit RGB), data (16-bit grey), normals (16-bit RGB), a float
    // height (EXR, through OpenImageIO).
    constexpr int kSize = 96;
    Image color(kSize, kSize, 3);
    Image data(kSize, kSize, 1);
    Image normal(kSize, kSize, 3);
    Image height(kSize, kSize, 1);
    for (int y = 0; y < kSize; ++y) {
      for (int x = 0; x < kSize; ++x) {
        float* c = color.pixel(x, y);
        c[0] = static_cast<float>(((x / 3) + (y / 3)) % 2);
        c[1] = static_cast<float>(x) / (kSize - 1);
        c[2] = 0.5f;
        data.pixel(x, y)[0] = static_cast<float>((x * 5 + y * 11) % 96) / 95.0f;
        const double tx = 0.35 * std::sin(x * 0.3);
        const double ty = 0.25 * std::cos(y * 0.2);
        const double tz = std::sqrt(1.0 - tx * tx - ty * ty);
        float* m = normal.pixel(x, y);
        m[0] = static_cast<float>(0.5 * (tx + 1.0));
        m[1] = static_cast<float>(0.5 * (ty + 1.0));
        m[2] = static_cast<float>(0.5 * (tz + 1.0));
        height.pixel(x, y)[0] = static_cast<float>(3.0 * std::sin(x * 0.1) * std::cos(y * 0.07));
      }
    }
    fs::create_directories(dir_ / "maps");
    write_image(path("maps/base.png"), color, PixelFormat::kUint8);
    write_image(path("maps/rough.png"), data, PixelFormat::kUint16);
    write_image(path("maps/nrm.png"), normal, PixelFormat::kUint16);
    write_image(path("maps/height.exr"), height, PixelFormat::kFloat);
    std::ofstream(path("f.json")) << R"({"features": [
      {"source": [20, 20], "target": [26, 17]}, {"source": [75, 22], "target": [72, 30]},
      {"source": [30, 75], "target": [35, 70]}, {"source": [70, 70], "target": [66, 72],
       "source_frame": {"angle_deg": 0, "scale": 1}, "target_frame": {"angle_deg": 15, "scale": 1.2}}]})";
  }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // A path as a shell argument (<UDIM> is a redirection to the shell).
  std::string quoted(const std::string& name) const { return "'" + path(name) + "'"; }

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

  std::string set_args() const {
    return "warp --features " + path("f.json") + " --in color=" + path("maps/base.png") +
           " --in data=" + path("maps/rough.png") + " --in normal=" + path("maps/nrm.png") + " --in " +
           path("maps/height.exr") + " --border clamp --backend cpu";
  }

  static std::string bytes(const std::string& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  texwarp::testing::TestFolder dir_{"texture_set_cli"};
};

TEST_F(TextureSetCliTest, EachOutputIsItsMapWarpedAlone) {
  CliRun r = run(set_args() + " --out-dir " + path("out"));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err,
              HasSubstr("wrote " + path("out/base.png") + " (96×96, 3 channels, uint8); sampled as color (sRGB)"));
  EXPECT_THAT(r.err, HasSubstr("out/rough.png (96×96, 1 channels, uint16); sampled as data"));
  EXPECT_THAT(r.err, HasSubstr("out/nrm.png (96×96, 3 channels, uint16); sampled as normal (opengl)"));
  EXPECT_THAT(r.err, HasSubstr("out/height.exr (96×96, 1 channels, float); sampled as data"));
  EXPECT_THAT(r.err, HasSubstr("texwarp: warped 4 maps with 4 features on cpu"));
  const std::vector<std::pair<std::string, std::string>> maps = {{"color=", "base.png"},
                                                                 {"data=", "rough.png"},
                                                                 {"normal=", "nrm.png"},
                                                                 {"", "height.exr"}};
  for (const auto& [role, file] : maps) {
    r = run("warp --features " + path("f.json") + " --in " + role + path("maps/" + file) + " --out " +
            path("alone-" + file) + " --border clamp --backend cpu");
    ASSERT_EQ(r.code, 0) << r.err;
    const Image alone = read_image(path("alone-" + file));
    const Image in_set = read_image(path("out/" + file));
    ASSERT_EQ(alone.channels, in_set.channels) << file;
    EXPECT_EQ(alone.pixels, in_set.pixels) << file;
    if (file != "height.exr") {
      EXPECT_TRUE(bytes(path("alone-" + file)) == bytes(path("out/" + file))) << file;
    }
  }
  // The warp moved the maps (an identity would pass the comparison too).
  EXPECT_NE(read_image(path("out/rough.png")).pixels, read_image(path("maps/rough.png")).pixels);
  // --out-dir with one input writes it under its own name.
  r = run("warp --features " + path("f.json") + " --in data=" + path("maps/rough.png") + " --out-dir " + path("one") +
          " --border clamp --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(bytes(path("one/rough.png")) == bytes(path("out/rough.png")));
}

TEST_F(TextureSetCliTest, BadSetsExitTwoNamingThemAndWriteNothing) {
  // Maps of different sizes.
  write_image(path("maps/small.png"), Image(48, 96, 1), PixelFormat::kUint8);
  CliRun r = run("warp --features " + path("f.json") + " --in " + path("maps/base.png") + " --in " +
                 path("maps/small.png") + " --out-dir " + path("out"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--in: the maps of one warp share its pixels: " + path("maps/small.png") +
                               " is 48×96, " + path("maps/base.png") + " 96×96"));
  // Two inputs with one file name.
  fs::create_directories(dir_ / "other");
  fs::copy_file(path("maps/rough.png"), path("other/rough.png"));
  r = run("warp --features " + path("f.json") + " --in " + path("maps/rough.png") + " --in " + path("other/rough.png") +
          " --out-dir " + path("out"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("would both be written as rough.png in --out-dir"));
  // --out with two inputs; neither --out nor --out-dir; an output over its own input.
  r = run("warp --features " + path("f.json") + " --in " + path("maps/base.png") + " --in " + path("maps/rough.png") +
          " --out " + path("x.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--out: 2 inputs (--in) write one output each: give --out-dir DIR"));
  r = run("warp --features " + path("f.json") + " --in " + path("maps/base.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("an output is required: --out or --out-dir"));
  r = run("warp --features " + path("f.json") + " --in " + path("maps/base.png") + " --out-dir " + path("maps"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("is the input itself"));
  // More maps than the limit.
  std::string many;
  for (int i = 0; i < 17; ++i) {
    fs::copy_file(path("maps/rough.png"), path("other/m" + std::to_string(i) + ".png"));
    many += " --in " + path("other/m" + std::to_string(i) + ".png");
  }
  r = run("warp --features " + path("f.json") + many + " --out-dir " + path("out"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--in: 17 inputs, more than the limit of 16 maps in one warp"));
  EXPECT_FALSE(fs::exists(path("out")) && !fs::is_empty(path("out")));
  EXPECT_FALSE(fs::exists(path("x.png")));

  // A map whose pixels are cut short fails the command after others were written: none of them appear.
  const std::string whole = bytes(path("maps/nrm.png"));
  std::ofstream(path("maps/cut.png"), std::ios::binary) << whole.substr(0, whole.size() / 2);
  fs::create_directories(dir_ / "out");
  r = run("warp --features " + path("f.json") + " --in " + path("maps/base.png") + " --in " + path("maps/rough.png") +
          " --in normal=" + path("maps/cut.png") + " --out-dir " + path("out") + " --backend cpu");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("cut.png"));
  EXPECT_TRUE(fs::is_empty(path("out")));

  // --out-dir through a link to nothing: the folder cannot be made (exit 1, an output that cannot be written), and
  // the user's link stays.
  fs::create_symlink(dir_ / "nowhere", dir_ / "dangling");
  r = run("warp --features " + path("f.json") + " --in " + path("maps/base.png") + " --in " + path("maps/rough.png") +
          " --out-dir " + path("dangling") + " --backend cpu");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--out-dir " + path("dangling") + ": cannot make the folder (File exists)"));
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "dangling")));
}

// An output that cannot be written fails the command before the map is computed. An EXR whose pixels are cut short
// tells the order: its headers are whole, and its error surfaces only once the map is done and its pixels are decoded
// (a PNG's chunks are checked before), so the command names the output, not the input (exit 1, as any output that
// cannot be written).
TEST_F(TextureSetCliTest, AnOutputThatCannotBeWrittenFailsBeforeTheMap) {
  const std::string whole = bytes(path("maps/height.exr"));
  std::ofstream(path("maps/cut.exr"), std::ios::binary) << whole.substr(0, whole.size() / 2);
  std::ofstream(path("a_file")) << "not a folder";
  const std::string warp = "warp --features " + path("f.json") + " --backend cpu --in " + path("maps/cut.exr");

  CliRun r = run(warp + " --out " + path("none/x.png"));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.err,
              HasSubstr("--out " + path("none/x.png") + ": cannot write there (" + path("none") + " does not exist)"));

  r = run(warp + " --out " + path("a_file/x.png"));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr(": cannot write there (" + path("a_file") + " is not a folder)"));

  r = run(warp + " --out " + path("x.exr") + " --certificate " + path("none/cert.json"));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--certificate " + path("none/cert.json") + ": cannot write there"));

  // A folder that cannot be made is refused in create_directories' words; where it can be, it is made only when the
  // maps are written, and goes again when the set fails there (here on the cut map).
  const std::string set = warp + " --in " + path("maps/base.png");
  r = run(set + " --out-dir " + path("a_file/sub"));
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("--out-dir " + path("a_file/sub") + ": cannot make the folder (Not a directory)"));
  r = run(set + " --out-dir " + path("new/sub"));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("cut.exr"));
  EXPECT_FALSE(fs::exists(path("new")));
}

TEST_F(TextureSetCliTest, UdimTilesAreWarpedAsTheirStitchedCanvasCutAgain) {
  // Tiles 1001, 1002 and 1011 of 48² (u, v: (0, 0), (1, 0), (0, 1)); 1012 is missing. The canvas is 96² with row
  // v = 1 on top: 1011 at (0, 0), 1001 at (0, 48), 1002 at (48, 48); the missing tile reads as the border
  // (transparent). The same canvas stitched here by hand, as RGBA, warped as one image and cut again, must give the
  // tiles' pixels exactly.
  const Image base = read_image(path("maps/base.png"));
  const std::vector<std::array<int, 3>> tiles = {{1001, 0, 48}, {1002, 48, 48}, {1011, 0, 0}};
  Image canvas(96, 96, 4, 3);
  fs::create_directories(dir_ / "udim");
  for (const auto& [number, x0, y0] : tiles) {
    Image tile(48, 48, 3);
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 48; ++x) {
        // Each tile its own content: the base map shifted by the tile's number.
        const float* from = base.pixel((x + number) % 96, (y + 2 * number) % 96);
        std::copy(from, from + 3, tile.pixel(x, y));
        std::copy(from, from + 3, canvas.pixel(x0 + x, y0 + y));
        canvas.pixel(x0 + x, y0 + y)[3] = 1.0f;
      }
    }
    write_image(path("udim/albedo." + std::to_string(number) + ".png"), tile, PixelFormat::kUint8);
  }
  write_image(path("canvas.png"), canvas, PixelFormat::kUint8);
  fs::create_directories(dir_ / "out");  // --out writes into an existing folder (--out-dir makes its own)
  CliRun r = run("warp --features " + path("f.json") + " --in " + quoted("udim/albedo.<UDIM>.png") + " --out " +
                 quoted("out/albedo.<UDIM>.png") + " --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, HasSubstr("(3 UDIM tiles of 48×48, 4 channels, uint8)"));
  r = run("warp --features " + path("f.json") + " --in " + path("canvas.png") + " --out " + path("canvas-out.png") +
          " --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  const Image whole = read_image(path("canvas-out.png"));
  for (const auto& [number, x0, y0] : tiles) {
    const Image tile = read_image(path("out/albedo." + std::to_string(number) + ".png"));
    ASSERT_EQ(tile.width, 48);
    ASSERT_EQ(tile.channels, 4);
    for (int y = 0; y < 48; ++y) {
      for (int x = 0; x < 48; ++x) {
        for (int c = 0; c < 4; ++c) {
          ASSERT_EQ(tile.pixel(x, y)[c], whole.pixel(x0 + x, y0 + y)[c]) << number << " " << x << "," << y;
        }
      }
    }
  }
  EXPECT_FALSE(fs::exists(path("out/albedo.1012.png")));  // only the tiles that exist are written
  // The warp moved pixels across tile seams: the output tiles are not the inputs.
  EXPECT_NE(read_image(path("out/albedo.1001.png")).pixels, read_image(path("udim/albedo.1001.png")).pixels);

  // A token that matches no tile; tiles of different sizes; an output without the token; a token on one image.
  r = run("warp --features " + path("f.json") + " --in " + quoted("udim/rough.<UDIM>.png") + " --out " +
          quoted("out/r.<UDIM>.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--in: \"" + path("udim/rough.<UDIM>.png") +
                               "\" matches no UDIM tile: no file for any of 1001–1100"));
  write_image(path("udim/albedo.1003.png"), Image(32, 48, 3), PixelFormat::kUint8);
  r = run("warp --features " + path("f.json") + " --in " + quoted("udim/albedo.<UDIM>.png") + " --out " +
          quoted("out2/a.<UDIM>.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("differ: tile 1003 is 32×48, 3 channels, uint8, tile 1001 48×48, 3 channels, uint8"));
  fs::remove(path("udim/albedo.1003.png"));
  r = run("warp --features " + path("f.json") + " --in " + quoted("udim/albedo.<UDIM>.png") + " --out " +
          path("out2/a.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--out: \"" + path("udim/albedo.<UDIM>.png") + "\" is a UDIM texture: its output " +
                               path("out2/a.png") + " needs the token <UDIM> too"));
  r = run("warp --features " + path("f.json") + " --in " + path("canvas.png") + " --out " +
          quoted("out2/a.<UDIM>.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("has the token <UDIM> but"));
  EXPECT_FALSE(fs::exists(path("out2")));
}

// MIP levels of a w×h image down to 1×1, each level half the one above (rounded down, at least 1).
int mip_levels(int w, int h) {
  int levels = 1;
  while (w > 1 || h > 1) {
    w = std::max(1, w / 2);
    h = std::max(1, h / 2);
    ++levels;
  }
  return levels;
}

TEST_F(TextureSetCliTest, TxAndTextureOutputsAreTiledMipMappedAndRecordTheirColourSpace) {
  fs::create_directories(dir_ / "tex");
  CliRun r = run("warp --features " + path("f.json") + " --in color=" + path("maps/base.png") + " --out " +
                 path("tex/base.tx") + " --border clamp --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  r = run("warp --features " + path("f.json") + " --in color=" + path("maps/base.png") + " --out " +
          path("tex/base.png") + " --border clamp --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  // A set with --texture: an EXR and a TIFF, each a texture.
  r = run("warp --features " + path("f.json") + " --in data=" + path("maps/height.exr") + " --in normal=" +
          path("maps/nrm.png") + " --out-dir " + path("tex") + " --border clamp --backend cpu --texture");
  EXPECT_EQ(r.code, 2);  // nrm.png keeps its name: PNG is not a texture format
  EXPECT_THAT(r.err, HasSubstr("--texture: " + path("tex/nrm.png") + ": a render-ready texture is a .tx"));
  write_image(path("maps/nrm.tif"), read_image(path("maps/nrm.png")), PixelFormat::kUint16);
  r = run("warp --features " + path("f.json") + " --in data=" + path("maps/height.exr") + " --in normal=" +
          path("maps/nrm.tif") + " --out-dir " + path("tex") + " --border clamp --backend cpu --texture");
  ASSERT_EQ(r.code, 0) << r.err;

  // The colour space as OpenImageIO 2.4 reads it back: a colour map's sRGB (TIFF keeps it in its EXIF); a data or
  // normal map asks for "Raw", which a TIFF does not keep and an EXR reads back as its float default, Linear. Each
  // file records its own in its ImageDescription (maketx's key=value words), which texwarp reads back.
  struct Expected {
    std::string file;
    std::string color_space;
    std::string recorded;
    OIIO::TypeDesc format;
    int channels;
  };
  for (const Expected& e : {Expected{"base.tx", "sRGB", "sRGB", OIIO::TypeDesc::UINT8, 3},
                            Expected{"height.exr", "Linear", "Raw", OIIO::TypeDesc::FLOAT, 1},
                            Expected{"nrm.tif", "", "Raw", OIIO::TypeDesc::UINT16, 3}}) {
    EXPECT_EQ(read_image_header(path("tex/" + e.file)).color_space, e.recorded) << e.file;
    auto in = OIIO::ImageInput::open(path("tex/" + e.file));
    ASSERT_TRUE(in) << e.file << ": " << OIIO::geterror();
    const OIIO::ImageSpec& spec = in->spec();
    EXPECT_THAT(spec.get_string_attribute("ImageDescription"), HasSubstr("oiio:ColorSpace=" + e.recorded)) << e.file;
    EXPECT_EQ(spec.width, 96) << e.file;
    EXPECT_EQ(spec.tile_width, 64) << e.file;
    EXPECT_EQ(spec.tile_height, 64) << e.file;
    EXPECT_EQ(spec.format, e.format) << e.file;
    EXPECT_EQ(spec.nchannels, e.channels) << e.file;
    EXPECT_EQ(spec.get_string_attribute("oiio:ColorSpace"), e.color_space) << e.file;
    int levels = 0;
    int w = 0;
    while (in->seek_subimage(0, levels)) {
      w = in->spec().width;
      EXPECT_GT(in->spec().tile_width, 0) << e.file << " level " << levels;
      ++levels;
    }
    EXPECT_EQ(levels, mip_levels(96, 96)) << e.file;
    EXPECT_EQ(w, 1) << e.file;
  }
  // Level 0 of the .tx holds the warped pixels: those of the PNG written from the same warp.
  auto in = OIIO::ImageInput::open(path("tex/base.tx"));
  ASSERT_TRUE(in);
  std::vector<float> tx(std::size_t{96} * 96 * 3);
  ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, tx.data()));
  const Image png = read_image(path("tex/base.png"));
  float worst = 0.0f;
  for (std::size_t i = 0; i < tx.size(); ++i) worst = std::max(worst, std::abs(tx[i] - png.pixels[i]));
  EXPECT_LE(worst, 0.5f / 255.0f);
  // And each output equals its map warped alone as a texture (level 0, read through texwarp).
  r = run("warp --features " + path("f.json") + " --in data=" + path("maps/height.exr") + " --out " +
          path("alone.exr") + " --border clamp --backend cpu");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(read_image(path("tex/height.exr")).pixels, read_image(path("alone.exr")).pixels);
}

}  // namespace
}  // namespace texwarp
