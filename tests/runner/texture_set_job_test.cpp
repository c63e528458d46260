// Texture sets in image jobs ("images", issue 30): the map of the output grid is computed once and every map sampled
// with its own role; each output must equal the same map warped alone by a single-image job, byte for byte. The report
// lists every map and the result files carry their roles; a <UDIM> path is warped as its canvas and written as the
// same tiles; output.texture writes .tx files; bad sets are refused at the JSON path of the offender, on submission
// and on the run alike, and a set that fails part way leaves none of its files.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

#include "test_folder.hpp"
#include "test_jobs.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/base64.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/runner/local_input_resolver.hpp"

namespace texwarp::runner {
namespace {

namespace fs = std::filesystem;

class TextureSetJobTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(dir_ / "scratch");
    // Three maps of one asset, 64², each of its own kind: sRGB colour (8-bit RGB), data (16-bit grey), normals
    // (16-bit RGB, tilted differently across the map).
    Image color(64, 64, 3);
    Image data(64, 64, 1);
    Image normal(64, 64, 3);
    for (int y = 0; y < 64; ++y) {
      for (int x = 0; x < 64; ++x) {
        float* c = color.pixel(x, y);
        c[0] = static_cast<float>(((x / 4) + (y / 4)) % 2);
        c[1] = static_cast<float>(x) / 63.0f;
        c[2] = static_cast<float>(y) / 63.0f;
        data.pixel(x, y)[0] = static_cast<float>((x * 7 + y * 13) % 64) / 63.0f;
        const double tx = 0.4 * std::sin(x * 0.2);
        const double ty = 0.3 * std::cos(y * 0.15);
        const double tz = std::sqrt(1.0 - tx * tx - ty * ty);
        float* n = normal.pixel(x, y);
        n[0] = static_cast<float>(0.5 * (tx + 1.0));
        n[1] = static_cast<float>(0.5 * (ty + 1.0));
        n[2] = static_cast<float>(0.5 * (tz + 1.0));
      }
    }
    write_image((dir_ / "albedo.png").string(), color, PixelFormat::kUint8);
    write_image((dir_ / "rough.png").string(), data, PixelFormat::kUint16);
    write_image((dir_ / "nrm.png").string(), normal, PixelFormat::kUint16);
  }

  // Runs `job` in a fresh output folder `name`; the job's paths are relative to the test folder.
  JobOutput run(const nlohmann::json& job, const std::string& name) {
    const fs::path out = dir_ / name;
    fs::create_directories(out);
    const proto::JobSpec spec = proto::decode_job_spec(job);
    LocalInputResolver inputs(dir_.path(), dir_ / "scratch");
    return run_job(spec, inputs, backends_, out, {}, {});
  }

  // Where validate_job and run_job refuse `job` (they must agree); the run wrote nothing.
  std::string refusal(const nlohmann::json& job) {
    const proto::JobSpec spec = proto::decode_job_spec(job);
    LocalInputResolver inputs(dir_.path(), dir_ / "scratch");
    fs::create_directories(dir_ / "refused");
    std::string on_submission = "(accepted)";
    std::string on_run = "(accepted)";
    try {
      validate_job(spec, inputs, {});
    } catch (const InputError& e) {
      on_submission = e.what();
    }
    try {
      run_job(spec, inputs, backends_, dir_ / "refused", {}, {});
    } catch (const InputError& e) {
      on_run = e.what();
    }
    EXPECT_EQ(on_submission, on_run);
    EXPECT_TRUE(fs::is_empty(dir_ / "refused"));
    return on_run;
  }

  static std::string decode_error(const nlohmann::json& job) {
    try {
      proto::decode_job_spec(job);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(accepted)";
  }

  static nlohmann::json set_job(const nlohmann::json& features) {
    return {{"images",
             {{{"path", "albedo.png"}, {"role", "color"}},
              {{"path", "rough.png"}, {"role", "data"}, {"name", "roughness"}},
              {{"path", "nrm.png"}, {"role", "normal"}}}},
            {"warp", {{"alpha", 2.0}, {"tolerance_px", 0.01}, {"features", features}}},
            {"output", {{"border", "clamp"}}}};
  }

  static nlohmann::json single_job(const nlohmann::json& set, std::size_t i) {
    nlohmann::json job = set;
    job.erase("images");
    job["image"] = set["images"][i];
    job["image"].erase("name");
    return job;
  }

  // The set's output `file` holds exactly the pixels of map `i` warped alone.
  void expect_same_as_alone(const nlohmann::json& set, std::size_t i, const std::string& file) {
    const std::string alone = "alone-" + std::to_string(i);
    const JobOutput out = run(single_job(set, i), alone);
    ASSERT_EQ(out.files.front().name, "warped.png");
    const Image a = read_image((dir_ / alone / "warped.png").string());
    const Image b = read_image((dir_ / "set" / file).string());
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.channels, b.channels);
    EXPECT_EQ(a.pixels, b.pixels) << file;
    // The files themselves are the same bytes (same encoder, same pixels).
    std::ifstream fa(dir_ / alone / "warped.png", std::ios::binary);
    std::ifstream fb(dir_ / "set" / file, std::ios::binary);
    const std::string ba((std::istreambuf_iterator<char>(fa)), std::istreambuf_iterator<char>());
    const std::string bb((std::istreambuf_iterator<char>(fb)), std::istreambuf_iterator<char>());
    EXPECT_TRUE(ba == bb) << file;
  }

  texwarp::testing::TestFolder dir_{"texture_set"};
  BackendCache backends_{proto::DeviceSpec::cpu()};
};

TEST_F(TextureSetJobTest, EveryMapEqualsItsOwnSingleImageJob) {
  const nlohmann::json job = set_job(testing::image_job_features());
  const JobOutput out = run(job, "set");
  std::vector<std::string> names;
  std::vector<std::optional<proto::ImageRole>> roles;
  for (const JobFile& f : out.files) {
    names.push_back(f.name);
    roles.push_back(f.role);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"albedo.png", "roughness.png", "nrm.png", "report.json"}));
  EXPECT_EQ(roles, (std::vector<std::optional<proto::ImageRole>>{proto::ImageRole::kColor, proto::ImageRole::kData,
                                                                 proto::ImageRole::kNormal, std::nullopt}));
  expect_same_as_alone(job, 0, "albedo.png");
  expect_same_as_alone(job, 1, "roughness.png");
  expect_same_as_alone(job, 2, "nrm.png");

  // The report: every map with its sampling; input and output at the top are the first map's; it round-trips.
  ASSERT_TRUE(out.report.image && out.report.image->maps);
  const std::vector<proto::MapReport>& maps = *out.report.image->maps;
  ASSERT_EQ(maps.size(), 3u);
  EXPECT_EQ(maps[1].name, "roughness");
  EXPECT_EQ(maps[1].output.file, "roughness.png");
  EXPECT_EQ(maps[1].input.channels, 1);
  EXPECT_EQ(maps[1].output.pixel_format, PixelFormat::kUint16);
  ASSERT_TRUE(maps[0].output.sampling && maps[1].output.sampling && maps[2].output.sampling);
  EXPECT_EQ(maps[0].output.sampling->role, proto::ImageRole::kColor);
  EXPECT_EQ(maps[0].output.sampling->color_space, "sRGB");
  EXPECT_EQ(maps[1].output.sampling->role, proto::ImageRole::kData);
  EXPECT_EQ(maps[2].output.sampling->role, proto::ImageRole::kNormal);
  EXPECT_EQ(out.report.image->output, maps[0].output);
  EXPECT_EQ(out.report.image->input, maps[0].input);
  for (const proto::MapReport& m : maps) EXPECT_GT(m.write_s, 0.0);
  EXPECT_EQ(proto::decode_job_report(proto::encode_job_report(out.report)), out.report);
  // One map of the output grid for the three: the certificate's pathlines are a single map's.
  const JobOutput alone = run(single_job(job, 0), "alone-again");
  ASSERT_TRUE(out.report.certificate && alone.report.certificate);
  EXPECT_EQ(out.report.certificate->pathlines, alone.report.certificate->pathlines);
  EXPECT_FALSE(alone.report.image->maps);  // a single image's report keeps its shape
}

TEST_F(TextureSetJobTest, AWholePixelTranslationCopiesMapsAndSamplesTheNormalMapAsAlone) {
  // One feature: a translation by (3, −2) px, a closed form moving pixel centres onto pixel centres. Colour and data
  // are copied; the normal map needs the grid's positions (its repair pass): both as when warped alone.
  const nlohmann::json features = {{{"source", {20, 20}}, {"target", {23, 18}}}};
  const nlohmann::json job = set_job(features);
  const JobOutput out = run(job, "set");
  EXPECT_EQ(out.report.method, proto::WarpMethodReport::kClosedForm);
  expect_same_as_alone(job, 0, "albedo.png");
  expect_same_as_alone(job, 2, "nrm.png");
  const Image src = read_image((dir_ / "albedo.png").string());
  const Image moved = read_image((dir_ / "set" / "albedo.png").string());
  EXPECT_EQ(moved.pixel(30, 30)[0], src.pixel(27, 32)[0]);  // output (x, y) pulls source (x − 3, y + 2)
}

TEST_F(TextureSetJobTest, BadSetsAreRefusedAtTheirPathWithNothingWritten) {
  nlohmann::json job = set_job(testing::image_job_features());
  // A map of another size.
  write_image((dir_ / "small.png").string(), Image(32, 64, 1), PixelFormat::kUint8);
  nlohmann::json bad = job;
  bad["images"][2] = {{"path", "small.png"}};
  EXPECT_EQ(refusal(bad),
            "$.images[2]: is 32×64, images[0] 64×64: the maps of a set share one warp, and so their size");
  // Two maps with one output name (decoded: the codec refuses it).
  bad = job;
  bad["images"][1]["name"] = "albedo";
  EXPECT_EQ(decode_error(bad),
            "$.images[1]: images 0 and 1 are both named \"albedo\": each map's output needs its own name");
  // Names that are not file names; a blob or inline map without one.
  bad = job;
  bad["images"][1]["name"] = "../x";
  EXPECT_NE(decode_error(bad).find("$.images[1].name: \"../x\" is not an output name"), std::string::npos);
  bad = job;
  bad["images"][0] = {{"base64", "aGVsbG8="}};
  EXPECT_EQ(decode_error(bad),
            "$.images[0].name: required for a blob, base64 or tiles image: the name its output is written under");
  // More maps than the limit, none, and both "image" and "images".
  bad = job;
  for (int i = 0; i < 17; ++i) bad["images"].push_back({{"path", "albedo.png"}, {"name", "a" + std::to_string(i)}});
  EXPECT_EQ(decode_error(bad), "$.images: 20 images: a texture set has 1 to 16 maps");
  bad["images"] = nlohmann::json::array();
  EXPECT_EQ(decode_error(bad), "$.images: 0 images: a texture set has 1 to 16 maps");
  bad = job;
  bad["image"] = {{"path", "albedo.png"}};
  EXPECT_NE(decode_error(bad).find("give exactly one of \"image\", \"images\""), std::string::npos);
  // A mesh job's warped texture is the region's frame: no <UDIM> path, in a set or alone.
  nlohmann::json mesh = testing::mesh_job();
  mesh.erase("image");
  mesh["images"] = job["images"];
  mesh["images"][1] = {{"path", "tile.<UDIM>.png"}, {"name", "tiles"}};
  write_image((dir_ / "tile.1001.png").string(), Image(64, 64, 1), PixelFormat::kUint8);
  const std::string why = ": a mesh job warps its texture onto the region's frame, one image: give one tile's file";
  EXPECT_EQ(refusal(mesh).substr(0, 16 + why.size()), "$.images[1].path" + why);
  mesh.erase("images");
  mesh["image"] = {{"path", "tile.<UDIM>.png"}};
  EXPECT_EQ(refusal(mesh).substr(0, 12 + why.size()), "$.image.path" + why);
}

TEST_F(TextureSetJobTest, AMeshJobSamplesEveryMapThroughTheRegionsOneWarp) {
  // The three maps on a mesh job's region: each warped texture equals that map's own single-image mesh job, byte for
  // byte, the UVs are the same, the report lists the maps and the glTF-less outputs carry their roles.
  nlohmann::json job = testing::mesh_job();
  job.erase("image");
  job["images"] = set_job(testing::image_job_features())["images"];
  job["output"] = {{"width", 96}, {"height", 80}, {"border", "clamp"}};
  job["mesh"]["obj_uv"] = "warped";
  const JobOutput out = run(job, "set");
  std::vector<std::string> names;
  for (const JobFile& f : out.files) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"mesh.obj", "uvs.json", "albedo.png", "roughness.png", "nrm.png",
                                             "report.json"}));
  EXPECT_EQ(out.files[4].role, proto::ImageRole::kNormal);
  ASSERT_TRUE(out.report.mesh && out.report.mesh->maps);
  const std::vector<proto::MapReport>& maps = *out.report.mesh->maps;
  ASSERT_EQ(maps.size(), 3u);
  EXPECT_EQ(maps[1].output.file, "roughness.png");
  EXPECT_EQ(maps[1].output.width, 96);
  EXPECT_EQ(maps[1].output.height, 80);
  ASSERT_TRUE(maps[2].output.sampling);
  EXPECT_EQ(maps[2].output.sampling->role, proto::ImageRole::kNormal);
  EXPECT_EQ(out.report.mesh->texture_sampling, maps[0].output.sampling);
  EXPECT_EQ(proto::decode_job_report(proto::encode_job_report(out.report)), out.report);
  const auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  // The OBJ names the three warped textures its UVs point into.
  EXPECT_NE(bytes(dir_ / "set" / "mesh.obj").find("the warped textures albedo.png, roughness.png and nrm.png"),
            std::string::npos);
  const std::array<std::string, 3> files{"albedo.png", "roughness.png", "nrm.png"};
  for (std::size_t i = 0; i < files.size(); ++i) {
    nlohmann::json alone = single_job(job, i);
    const std::string folder = "mesh-alone-" + std::to_string(i);
    const JobOutput one = run(alone, folder);
    ASSERT_TRUE(one.report.mesh);
    EXPECT_FALSE(one.report.mesh->maps);
    EXPECT_EQ(one.report.certificate->pathlines, out.report.certificate->pathlines);
    const Image a = read_image((dir_ / folder / "warped.png").string());
    const Image b = read_image((dir_ / "set" / files[i]).string());
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.channels, b.channels);
    EXPECT_EQ(a.pixels, b.pixels) << files[i];
    EXPECT_EQ(bytes(dir_ / folder / "warped.png"), bytes(dir_ / "set" / files[i])) << files[i];
    EXPECT_EQ(bytes(dir_ / folder / "uvs.json"), bytes(dir_ / "set" / "uvs.json"));
  }
}

TEST_F(TextureSetJobTest, ASetThatFailsPartWayLeavesNoneOfItsFiles) {
  // The third map's header is whole, its pixels cut short: the run fails on it after two maps were written.
  std::ifstream in(dir_ / "nrm.png", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir_ / "cut.png", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  nlohmann::json job = set_job(testing::image_job_features());
  job["images"][2] = {{"path", "cut.png"}, {"role", "normal"}};
  fs::create_directories(dir_ / "set");
  try {
    run(job, "set");
    ADD_FAILURE() << "a truncated map was warped";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).substr(0, 12), "$.images[2]:");
  }
  EXPECT_TRUE(fs::is_empty(dir_ / "set"));
}

TEST_F(TextureSetJobTest, SetJobsRoundTripTheCodecWithNamesFromPaths) {
  const proto::JobSpec spec = proto::decode_job_spec(set_job(testing::image_job_features()));
  ASSERT_EQ(spec.images.size(), 3u);
  EXPECT_TRUE(spec.is_set());
  EXPECT_EQ(spec.images[0].name, "albedo");  // the path's file name without its extension
  EXPECT_EQ(spec.images[1].name, "roughness");
  EXPECT_EQ(spec.images[2].source.role, proto::ImageRole::kNormal);
  const nlohmann::json encoded = proto::encode_job_spec(spec);
  EXPECT_FALSE(encoded.contains("image"));
  EXPECT_EQ(encoded["images"][0]["name"], "albedo");
  EXPECT_EQ(proto::decode_job_spec(encoded), spec);
}

TEST_F(TextureSetJobTest, UdimPathsAreWarpedAsTheirCanvasAndWrittenAsTiles) {
  // Tiles 1001 and 1012 of 32² (u, v: (0, 0) and (1, 1)); 1002 and 1011 missing. The canvas is 64²: 1012 top right,
  // 1001 bottom left; with a clamp border a missing tile's pixel is the nearest texel of a tile that exists (found
  // here by exhaustive search, ties to 1001). The same canvas as one file, warped by a single-image job, must give the
  // tiles' pixels exactly.
  const Image albedo = read_image((dir_ / "albedo.png").string());
  Image canvas(64, 64, 3);
  fs::create_directories(dir_ / "udim");
  const std::vector<std::array<int, 3>> present{{1001, 0, 32}, {1012, 32, 0}};
  for (const auto& [number, x0, y0] : present) {
    Image tile(32, 32, 3);
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 32; ++x) {
        for (int c = 0; c < 3; ++c) {
          tile.pixel(x, y)[c] = canvas.pixel(x0 + x, y0 + y)[c] = albedo.pixel(x0 + x, y0 + y)[c];
        }
      }
    }
    write_image((dir_ / "udim" / ("base.color." + std::to_string(number) + ".png")).string(), tile,
                PixelFormat::kUint8);
  }
  for (const auto& [mx, my] : std::vector<std::array<int, 2>>{{0, 0}, {32, 32}}) {  // tiles 1011 and 1002: missing
    for (int y = my; y < my + 32; ++y) {
      for (int x = mx; x < mx + 32; ++x) {
        int best = -1, bx = 0, by = 0;
        for (const auto& [number, x0, y0] : present) {
          for (int ty = y0; ty < y0 + 32; ++ty) {
            for (int tx = x0; tx < x0 + 32; ++tx) {
              const int d = (tx - x) * (tx - x) + (ty - y) * (ty - y);
              if (best < 0 || d < best) std::tie(best, bx, by) = std::tuple(d, tx, ty);
            }
          }
        }
        for (int c = 0; c < 3; ++c) canvas.pixel(x, y)[c] = canvas.pixel(bx, by)[c];
      }
    }
  }
  write_image((dir_ / "canvas.png").string(), canvas, PixelFormat::kUint8);
  nlohmann::json job = set_job(testing::image_job_features());
  job["images"] = {{{"path", "udim/base.color.<UDIM>.png"}}, {{"path", "rough.png"}}};
  job["images"][1] = {{"path", "canvas.png"}, {"name", "whole"}};
  const JobOutput out = run(job, "set");
  std::vector<std::string> names;
  for (const JobFile& f : out.files) names.push_back(f.name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"base.color.1001.png", "base.color.1012.png", "whole.png", "report.json"}));
  ASSERT_TRUE(out.report.image && out.report.image->maps);
  EXPECT_EQ((*out.report.image->maps)[0].output.file, "base.color.<UDIM>.png");
  EXPECT_EQ((*out.report.image->maps)[0].input.width, 64);  // the canvas
  const Image whole = read_image((dir_ / "set" / "whole.png").string());
  for (const auto& [number, x0, y0] : std::vector<std::array<int, 3>>{{1001, 0, 32}, {1012, 32, 0}}) {
    const Image tile = read_image((dir_ / "set" / ("base.color." + std::to_string(number) + ".png")).string());
    ASSERT_EQ(tile.width, 32);
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 32; ++x) {
        for (int c = 0; c < 3; ++c) ASSERT_EQ(tile.pixel(x, y)[c], whole.pixel(x0 + x, y0 + y)[c]) << number;
      }
    }
  }
  // A token matching nothing is refused at its path.
  job["images"][0] = {{"path", "udim/none.<UDIM>.png"}};
  EXPECT_EQ(refusal(job), "$.images[0].path: \"udim/none.<UDIM>.png\" matches no UDIM tile: no file for any of "
                          "1001–1100");
}

TEST_F(TextureSetJobTest, UdimTilesGivenOneByOneAreWarpedAsTheirPathWouldBe) {
  // Tiles 1001 and 1012 as files under a <UDIM> path, and the same files given inline one by one ("tiles", as a
  // client sends what texwarpd cannot read from its disk): the same warped tiles, byte for byte.
  const Image albedo = read_image((dir_ / "albedo.png").string());
  fs::create_directories(dir_ / "udim");
  nlohmann::json tiles = nlohmann::json::array();
  for (const auto& [number, x0, y0] : std::vector<std::array<int, 3>>{{1012, 32, 0}, {1001, 0, 32}}) {
    Image tile(32, 32, 3);
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 32; ++x) {
        for (int c = 0; c < 3; ++c) tile.pixel(x, y)[c] = albedo.pixel(x0 + x, y0 + y)[c];
      }
    }
    const fs::path file = dir_ / "udim" / ("base." + std::to_string(number) + ".png");
    write_image(file.string(), tile, PixelFormat::kUint8);
    std::ifstream in(file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    tiles.push_back({{"tile", number}, {"base64", proto::base64_encode(bytes)}});
  }
  nlohmann::json by_path = single_job(set_job(testing::image_job_features()), 0);
  by_path["image"] = {{"path", "udim/base.<UDIM>.png"}, {"role", "color"}};
  nlohmann::json by_tiles = by_path;
  by_tiles["image"] = {{"tiles", tiles}, {"role", "color"}};
  const JobOutput a = run(by_path, "path");
  const JobOutput b = run(by_tiles, "tiles");
  std::vector<std::string> names;
  for (const JobFile& f : b.files) names.push_back(f.name);
  EXPECT_EQ(names, (std::vector<std::string>{"warped.1001.png", "warped.1012.png", "report.json"}));
  ASSERT_EQ(a.files.size(), b.files.size());
  const auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  for (const char* tile : {"warped.1001.png", "warped.1012.png"}) {
    EXPECT_FALSE(bytes(dir_ / "path" / tile).empty()) << tile;
    EXPECT_EQ(bytes(dir_ / "path" / tile), bytes(dir_ / "tiles" / tile)) << tile;
  }
  // The job round-trips the codec with its tiles; in a set a tiles map needs a name.
  const proto::JobSpec spec = proto::decode_job_spec(by_tiles);
  EXPECT_EQ(proto::decode_job_spec(proto::encode_job_spec(spec)), spec);
  nlohmann::json set = set_job(testing::image_job_features());
  set["images"][0] = by_tiles["image"];
  EXPECT_EQ(decode_error(set),
            "$.images[0].name: required for a blob, base64 or tiles image: the name its output is written under");
  // Bad tiles: a number outside 1001–1100, one given twice, tiles of different sizes, a blob in a local run.
  nlohmann::json bad = by_tiles;
  bad["image"]["tiles"][0]["tile"] = 1101;
  EXPECT_EQ(decode_error(bad), "$.image.tiles[0].tile: expected a UDIM tile number from 1001 to 1100, got 1101");
  bad = by_tiles;
  bad["image"]["tiles"][1]["tile"] = 1012;
  EXPECT_EQ(decode_error(bad), "$.image.tiles[1].tile: tile 1012 is given twice (tiles[0] and tiles[1])");
  bad = by_tiles;
  std::ifstream small_in(dir_ / "albedo.png", std::ios::binary);
  bad["image"]["tiles"][1]["base64"] =
      proto::base64_encode(std::string((std::istreambuf_iterator<char>(small_in)), std::istreambuf_iterator<char>()));
  EXPECT_NE(refusal(bad).find("$.image.tiles: the tiles of \"tiles\" differ: tile 1012 is 32×32"), std::string::npos)
      << refusal(bad);
  bad = by_tiles;
  bad["image"]["tiles"][1] = {{"tile", 1001}, {"blob", "sha256:" + std::string(64, 'a')}};
  EXPECT_NE(refusal(bad).find("$.image.tiles[1].blob: a blob id names a file in a texwarpd's store"), std::string::npos)
      << refusal(bad);
}

TEST_F(TextureSetJobTest, TextureOutputsAreTxFilesHoldingTheWarpedPixels) {
  nlohmann::json job = set_job(testing::image_job_features());
  job["output"]["file_format"] = "tiff";
  job["output"]["texture"] = true;
  const JobOutput out = run(job, "set");
  std::vector<std::string> names;
  for (const JobFile& f : out.files) names.push_back(f.name + " " + f.media_type);
  EXPECT_EQ(names, (std::vector<std::string>{"albedo.tx image/tiff", "roughness.tx image/tiff", "nrm.tx image/tiff",
                                             "report.json application/json"}));
  // Level 0 holds what the PNG job writes (same pixels, same 8 and 16 bits).
  const JobOutput png = run(single_job(set_job(testing::image_job_features()), 1), "png");
  const Image tx = read_image((dir_ / "set" / "roughness.tx").string());
  const Image plain = read_image((dir_ / "png" / "warped.png").string());
  ASSERT_EQ(tx.pixels.size(), plain.pixels.size());
  float worst = 0.0f;
  for (std::size_t i = 0; i < tx.pixels.size(); ++i) worst = std::max(worst, std::abs(tx.pixels[i] - plain.pixels[i]));
  EXPECT_LE(worst, 0.5f / 65535.0f);
  // A PNG cannot be a texture.
  job["output"]["file_format"] = "png";
  EXPECT_EQ(decode_error(job), "$.output.texture: a render-ready texture is a TIFF (.tx) or an EXR: give "
                               "\"file_format\": \"tiff\" or \"exr\"");
}

}  // namespace
}  // namespace texwarp::runner
