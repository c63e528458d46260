// `texwarp map-mesh` through the real binary: the shipped spot example end to end (OBJ, warped texture,
// report; the input's own lines kept), the UV origin option, a .glb in and out, the memory budget's bounds on the mesh
// and its refinement, and exit code 2 with a message naming the file for bad inputs.
#include <sys/wait.h>
#include <unistd.h>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <zlib.h>
#include <nlohmann/json.hpp>

#include "gltf_test_files.hpp"
#include "mesh_test_shapes.hpp"
#include "test_folder.hpp"
#include "texwarp/core/image.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/mesh/gltf_mesh.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"

namespace {

using ::testing::HasSubstr;

const std::string kCli = TEXWARP_CLI;
const std::string kSpot = std::string(TEXWARP_SOURCE_DIR) + "/examples/mesh/spot.obj";
const std::string kTexture = std::string(TEXWARP_SOURCE_DIR) + "/examples/astronaut.png";
const std::string kExamples = std::string(TEXWARP_SOURCE_DIR) + "/examples/mesh/";
constexpr int kSpotVt = 3225;  // spot.obj's own vt lines

struct CliRun {
  int code = -1;
  std::string output;  // stdout and stderr
};

CliRun run(const std::string& args) {
  CliRun r;
  FILE* pipe = popen((kCli + " " + args + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string write(const std::string& dir, const std::string& name, const std::string& text) {
  std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::vector<std::array<double, 2>> read_vt(const std::string& obj) {
  std::ifstream in(obj);
  std::vector<std::array<double, 2>> vt;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("vt ", 0) == 0) {
      std::array<double, 2> uv{};
      std::sscanf(line.c_str(), "vt %lf %lf", uv.data(), &uv[1]);
      vt.push_back(uv);
    }
  }
  return vt;
}

// A flat 6×6 grid as dir/grid.glb and five features on it as dir/features.json (four vertex pins around a feature
// inside face 24, on the astronaut's pixels); returns the grid.
texwarp::mesh::TriangleMesh write_grid_glb(const std::string& dir) {
  texwarp::mesh::TriangleMesh grid = texwarp::mesh::testing::flat_grid(6, 6);
  write(dir, "grid.glb", texwarp::mesh::testing::glb_bytes(texwarp::mesh::testing::gltf_parts(grid)));
  write(dir, "features.json", R"({"features": [
      {"source": [100, 400], "target": {"vertex": 8}}, {"source": [420, 410], "target": {"vertex": 12}},
      {"source": [410, 90], "target": {"vertex": 40}}, {"source": [90, 100], "target": {"vertex": 36}},
      {"source": [260, 250], "target": {"face": 24, "barycentric": [0.2, 0.3, 0.5]}}]})");
  return grid;
}

std::string base_args() {
  return "map-mesh --backend cpu --mesh " + kSpot + " --texture " + kTexture + " --features " + kExamples +
         "spot_head_features.json --region " + kExamples + "spot_head_region.json";
}

TEST(MapMeshCli, SpotExampleEndToEnd) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  // The input's faces kept (--no-refine), so are its lines; the refined default: RefineMakesEveryFeatureExact.
  const CliRun r = run(base_args() + " --no-refine --optimize none --out-obj " + dir + "/spot.obj --out-texture " +
                       dir + "/warped.png --report " + dir + "/report.json --per-triangle");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("1800 region faces, 12 features"));

  std::ifstream report_file(dir + "/report.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  EXPECT_EQ(report.at("uv_origin"), "bottom_left");
  EXPECT_EQ(report.at("flipped_triangles").get<int>(), 0);
  EXPECT_LE(report.at("max_residual_px").get<double>(), 1.0);
  EXPECT_GE(report.at("l2_stretch").get<double>(), 1.0);
  EXPECT_GT(report.at("l2_shear").get<double>(), 0.0);
  EXPECT_LT(report.at("l2_shear").get<double>(), 1.0);
  ASSERT_EQ(report.at("features").size(), 12u);
  double worst = 0.0;
  for (const auto& f : report.at("features")) worst = std::max(worst, f.at("residual_px").get<double>());
  EXPECT_EQ(worst, report.at("max_residual_px").get<double>());
  EXPECT_EQ(report.at("warp").at("gradient_features").get<int>(), 1);
  EXPECT_EQ(report.at("region").at("faces").get<int>(), 1800);
  EXPECT_EQ(report.at("triangles").size(), 1800u);
  std::printf("map-mesh spot: L2 stretch %.4f, L2 shear %.4f, flips %d, max residual %.4f px, %.2f s\n",
              report.at("l2_stretch").get<double>(), report.at("l2_shear").get<double>(),
              report.at("flipped_triangles").get<int>(), report.at("max_residual_px").get<double>(),
              report.at("seconds").get<double>());

  // The OBJ: the input's lines (its 2930 v, 3225 vt, 5856 f v/vt), a new vt per region vertex at the end, which
  // the 1800 region faces now point at.
  std::ifstream obj(dir + "/spot.obj");
  int v = 0, vt = 0, f_new = 0, f_old = 0;
  for (std::string line; std::getline(obj, line);) {
    if (line.rfind("v ", 0) == 0) ++v;
    if (line.rfind("vt ", 0) == 0) ++vt;
    int a = 0, ta = 0;
    if (std::sscanf(line.c_str(), "f %d/%d", &a, &ta) == 2) (ta > kSpotVt ? f_new : f_old)++;
  }
  EXPECT_EQ(v, 2930);
  EXPECT_EQ(vt, kSpotVt + report.at("region").at("vertices").get<int>());
  EXPECT_EQ(f_new, 1800);
  EXPECT_EQ(f_old, 5856 - 1800);
  const texwarp::ImageHeader warped = texwarp::read_image_header(dir + "/warped.png");
  EXPECT_EQ(warped.width, 512);
  EXPECT_EQ(warped.height, 512);
  std::filesystem::remove_all(dir);
}

// The default (refined, optimised): every feature (vertex, face and point targets) lands exactly, no UV triangle
// of the OBJ as written flips, the stretch went down, and the OBJ carries the input's vertices first and the new ones
// after, as the report counts them.
TEST(MapMeshCli, RefineMakesEveryFeatureExact) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  const CliRun r = run(base_args() + " --out-obj " + dir + "/refined.obj --report " + dir +
                       "/refined.json --per-triangle --per-vertex");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("refine: "));
  std::ifstream report_file(dir + "/refined.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  EXPECT_EQ(report.at("flipped_triangles").get<int>(), 0);
  EXPECT_TRUE(report.at("flips").empty());
  EXPECT_EQ(report.at("embedding").at("method"), "lscm");
  for (const auto& f : report.at("features")) EXPECT_LE(f.at("residual_px").get<double>(), 1e-3) << f.dump();
  const nlohmann::json& refinement = report.at("refinement");
  EXPECT_GT(refinement.at("feature_vertices").get<int>(), 0);
  int v = 0, faces = 0;
  std::ifstream obj(dir + "/refined.obj");
  for (std::string line; std::getline(obj, line);) {
    v += line.rfind("v ", 0) == 0 ? 1 : 0;
    faces += line.rfind("f ", 0) == 0 ? 1 : 0;
  }
  EXPECT_EQ(v, refinement.at("output_vertices").get<int>());
  EXPECT_EQ(faces, refinement.at("output_faces").get<int>());
  int added = 0;
  for (const auto& vertex : report.at("vertices")) added += vertex.contains("source") ? 1 : 0;
  EXPECT_EQ(added, refinement.at("added_vertices").get<int>());
  for (const auto& t : report.at("triangles")) EXPECT_TRUE(t.contains("source_face"));
  EXPECT_EQ(refinement.at("stop"), "flip_free");
  EXPECT_EQ(refinement.at("flipped_after").get<int>(), 0);
  EXPECT_TRUE(refinement.at("kept").get<bool>());
  const nlohmann::json& optimization = report.at("optimization");
  EXPECT_TRUE(optimization.at("applied").get<bool>());
  EXPECT_LT(report.at("l2_stretch").get<double>(), optimization.at("before").at("l2_stretch").get<double>());
  EXPECT_LT(optimization.at("energy_after").get<double>(), optimization.at("energy_before").get<double>());
  EXPECT_GE(report.at("max_aspect").get<double>(), 1.0);
  EXPECT_THAT(r.output, HasSubstr("optimize: L² stretch"));

  // Read back as a user's tool reads it: every region face's vt triangle counter-clockwise (v up), in floats.
  const std::vector<std::array<double, 2>> vt = read_vt(dir + "/refined.obj");
  std::ifstream again(dir + "/refined.obj");
  int region_faces = 0, clockwise = 0;
  for (std::string line; std::getline(again, line);) {
    std::array<int, 3> p{}, t{};
    if (std::sscanf(line.c_str(), "f %d/%d %d/%d %d/%d", p.data(), t.data(), &p[1], &t[1], &p[2], &t[2]) != 6) continue;
    ++region_faces;
    std::array<std::array<float, 2>, 3> uv{};
    for (int k = 0; k < 3; ++k) uv[k] = {static_cast<float>(vt[t[k] - 1][0]), static_cast<float>(vt[t[k] - 1][1])};
    const double cross = (double(uv[1][0]) - uv[0][0]) * (double(uv[2][1]) - uv[0][1]) -
                         (double(uv[1][1]) - uv[0][1]) * (double(uv[2][0]) - uv[0][0]);
    clockwise += cross > 0.0 ? 0 : 1;
  }
  EXPECT_EQ(region_faces, report.at("region").at("faces").get<int>());
  EXPECT_EQ(clockwise, 0);
}

// A pin outside the texture is refused naming it; nothing is written.
TEST(MapMeshCli, APinOutsideTheTextureIsRefused) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  const std::string features =
      write(dir, "out.json", R"({"features": [{"id": "eye", "source": [600, 20], "target": {"vertex": 158}}]})");
  const CliRun r = run("map-mesh --backend cpu --mesh " + kSpot + " --texture " + kTexture + " --features " + features +
                       " --region " + kExamples + "spot_head_region.json --out-obj " + dir + "/x.obj");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_THAT(r.output, HasSubstr("$.features[0].source: feature \"eye\" at (600.000000, 20.000000) px lies outside "
                                  "the 512×512 texture"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.obj"));
}

// --max-job-memory-mb bounds the mesh as texwarpd bounds a mesh job: a mesh that does not fit is refused naming it,
// and refinement adds vertices only as far as the budget leaves room, two faces of 1 536 bytes each per vertex (1 MiB
// more: 341 or 342 vertices more).
TEST(MapMeshCli, TheMemoryBudgetBoundsTheMeshAndItsRefinement) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  const CliRun refused = run(base_args() + " --max-job-memory-mb 1 --out-obj " + dir + "/x.obj");
  EXPECT_EQ(refused.code, 2) << refused.output;
  EXPECT_THAT(refused.output, HasSubstr(kSpot + ": this job needs about 9.3 MB (LSCM system and factor"));
  EXPECT_THAT(refused.output, HasSubstr("--max-job-memory-mb"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.obj"));

  auto limit = [&](const std::string& budget) {
    const CliRun r = run(base_args() + budget + " --out-obj " + dir + "/x.obj --report " + dir + "/x.json");
    EXPECT_EQ(r.code, 0) << r.output;
    std::ifstream in(dir + "/x.json");
    const nlohmann::json report = nlohmann::json::parse(in);
    EXPECT_EQ(report.at("flipped_triangles").get<int>(), 0);
    return report.at("refinement").at("vertex_limit").get<int>();
  };
  constexpr int kRegionVertices = 933;  // spot_head_region.json's, before its 2 features are made vertices
  const int tight = limit(" --max-job-memory-mb 12");
  const int looser = limit(" --max-job-memory-mb 13");
  EXPECT_GT(tight, kRegionVertices);
  EXPECT_LT(looser, 16 * kRegionVertices);
  EXPECT_GE(looser - tight, 341);
  EXPECT_LE(looser - tight, 342);
  EXPECT_EQ(limit(""), 16 * kRegionVertices);  // half the machine's memory: the 16× bound holds first

  // The same mesh as a .glb: what its document, BIN chunk and attributes keep for the output is charged too.
  const texwarp::mesh::TriangleMesh spot = texwarp::mesh::read_mesh_document(kSpot).mesh;
  const std::string glb = texwarp::mesh::testing::glb_bytes(texwarp::mesh::testing::gltf_parts(spot));
  write(dir, "spot.glb", glb);
  const std::uint64_t held =
      texwarp::mesh::parse_gltf_mesh(glb, true, {}, texwarp::proto::InputLocation::file("spot.glb")).held_bytes;
  EXPECT_GT(held, glb.size());  // the BIN chunk and the decoded attributes at least
  EXPECT_LT(held, 4 * glb.size());
  const CliRun as_glb = run("map-mesh --backend cpu --mesh " + dir + "/spot.glb --texture " + kTexture +
                            " --features " + kExamples + "spot_head_features.json --region " + kExamples +
                            "spot_head_region.json --max-job-memory-mb 1 --out-gltf " + dir + "/x.glb");
  EXPECT_EQ(as_glb.code, 2) << as_glb.output;
  EXPECT_THAT(as_glb.output, HasSubstr("the glTF document and attributes kept for the output"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/x.glb"));
}

// The first texture is decoded while the mesh is flattened: its source and decoding buffers count beside the LSCM
// system. A 2048² texture warped to 64² (clamp: no coverage channel) needs more there than in any of its own phases:
// 85 MiB admitted it when the decode came after the mapping (its largest phase 86 MB); now the flattening's phase of
// 93 MB is refused, naming the texture, and nothing is written.
TEST(MapMeshCli, TheFirstTexturesDecodeCountsBesideTheFlattening) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  texwarp::write_image(dir + "/big.png", texwarp::Image(2048, 2048, 3), texwarp::PixelFormat::kUint8);
  const std::string args = "map-mesh --backend cpu --mesh " + kSpot + " --texture " + dir + "/big.png --features " +
                           kExamples + "spot_head_features.json --region " + kExamples +
                           "spot_head_region.json --no-refine --optimize none --width 64 --height 64 --border clamp " +
                           "--out-texture " + dir + "/w.png --out-obj " + dir + "/s.obj";
  const CliRun refused = run(args + " --max-job-memory-mb 85");
  EXPECT_EQ(refused.code, 2) << refused.output;
  EXPECT_THAT(refused.output, HasSubstr(dir + "/big.png: this job needs about 93 MB (source 2048×2048 RGB as float 50 "
                                              "MB, decoding buffers 34 MB, LSCM system and factor 7.5 MB"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/w.png"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/s.obj"));
  const CliRun admitted = run(args + " --max-job-memory-mb 100");
  EXPECT_EQ(admitted.code, 0) << admitted.output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/w.png"));
}

TEST(MapMeshCli, UvOriginFlipsV) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  // The input's lines kept (--no-refine): its own vt lines must be the same in both.
  ASSERT_EQ(run(base_args() + " --no-refine --out-obj " + dir + "/bl.obj").code, 0);
  ASSERT_EQ(run(base_args() + " --no-refine --uv-origin top_left --out-obj " + dir + "/tl.obj").code, 0);
  const auto bl = read_vt(dir + "/bl.obj");
  const auto tl = read_vt(dir + "/tl.obj");
  ASSERT_EQ(bl.size(), tl.size());
  ASSERT_GT(bl.size(), static_cast<std::size_t>(kSpotVt));
  const std::size_t own = kSpotVt;
  for (std::size_t i = 0; i < own; ++i) EXPECT_EQ(bl[i], tl[i]);  // the input's own vt lines, kept
  for (std::size_t i = own; i < bl.size(); ++i) {
    EXPECT_NEAR(bl[i][0], tl[i][0], 1e-9);
    EXPECT_NEAR(bl[i][1], 1.0 - tl[i][1], 1e-9);
  }
  std::filesystem::remove_all(dir);
}

TEST(MapMeshCli, GlbInGlbOutWithTheWarpedTextureAsBaseColour) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  const texwarp::mesh::TriangleMesh grid = write_grid_glb(dir);
  const std::string args = "map-mesh --backend cpu --mesh " + dir + "/grid.glb --gltf-mesh grid --texture " + kTexture +
                           " --features " + dir + "/features.json --obj-uv warped --out-texture " + dir +
                           "/tex/warped.png --report " + dir + "/report.json --per-triangle";
  std::filesystem::create_directories(dir + "/tex");
  const CliRun r = run(args + " --out-gltf " + dir + "/out.glb");
  ASSERT_EQ(r.code, 0) << r.output;
  std::ifstream in(dir + "/out.glb", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const texwarp::mesh::GltfMesh back =
      texwarp::mesh::parse_gltf_mesh(bytes, true, {}, texwarp::proto::InputLocation::file("out.glb"));
  // Refined by default: the feature inside face 24 became a vertex, face 24 three faces (24 and two new ones).
  ASSERT_EQ(back.mesh.face_count(), grid.face_count() + 2);
  ASSERT_EQ(back.mesh.vertex_count(), grid.vertex_count() + 1);
  for (int f = 0; f < grid.face_count(); ++f) {
    if (f != 24) {
      EXPECT_EQ(back.mesh.faces[f], grid.faces[f]) << "face " << f;
    }
  }
  const texwarp::mesh::Vec3 expected =
      texwarp::mesh::interpolate(grid.corner(24, 0), grid.corner(24, 1), grid.corner(24, 2), {0.2, 0.3, 0.5});
  const texwarp::mesh::Vec3 added = back.mesh.vertices.back();
  EXPECT_NEAR(added.x, expected.x, 1e-6);
  EXPECT_NEAR(added.y, expected.y, 1e-6);
  EXPECT_NEAR(added.z, expected.z, 1e-6);
  for (const auto& uv : back.texcoord0) {  // into the warped texture, which has a margin around the embedding
    EXPECT_GT(uv[0], 0.0);
    EXPECT_LT(uv[0], 1.0);
    EXPECT_GT(uv[1], 0.0);
    EXPECT_LT(uv[1], 1.0);
  }
  EXPECT_EQ(back.document.at("images").back().at("uri"), "tex/warped.png");
  // --no-refine keeps the input's faces.
  ASSERT_EQ(run(args + " --no-refine --out-gltf " + dir + "/kept.glb").code, 0);
  std::ifstream kept_in(dir + "/kept.glb", std::ios::binary);
  const std::string kept_bytes((std::istreambuf_iterator<char>(kept_in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(
      texwarp::mesh::parse_gltf_mesh(kept_bytes, true, {}, texwarp::proto::InputLocation::file("kept.glb")).mesh.faces,
      grid.faces);
  const CliRun wrong = run(args + " --out-gltf " + dir + "/out.gltf");
  EXPECT_EQ(wrong.code, 2);
  EXPECT_THAT(wrong.output, HasSubstr("--out-gltf: the mesh is a .glb file: name the output .glb too"));
  std::filesystem::remove_all(dir);
}

// A texture set (several --texture, --out-dir): the warp's map is computed once and each map is sampled with its own
// role; every output equals that map warped alone (--out-texture), the report lists the maps, the glTF's base colour
// is the colour map; bad sets are refused before anything is written.
TEST(MapMeshCli, TheMapsOfATextureSetEachEqualTheirWarpAlone) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  write_grid_glb(dir);
  // A data map (one 16-bit channel) and a normal map (16-bit RGB) of the astronaut's size.
  texwarp::Image rough(512, 512, 1);
  texwarp::Image normals(512, 512, 3);
  for (int y = 0; y < 512; ++y) {
    for (int x = 0; x < 512; ++x) {
      rough.pixel(x, y)[0] = static_cast<float>(0.5 + 0.5 * std::sin(0.05 * x + 0.03 * y));
      const double tx = 0.4 * std::sin(0.1 * x);
      const double ty = 0.3 * std::cos(0.07 * y);
      const double n[3] = {tx, ty, std::sqrt(1.0 - tx * tx - ty * ty)};
      for (int c = 0; c < 3; ++c) normals.pixel(x, y)[c] = static_cast<float>(0.5 * n[c] + 0.5);
    }
  }
  texwarp::write_image(dir + "/rough.png", rough, texwarp::PixelFormat::kUint16);
  texwarp::write_image(dir + "/nrm.png", normals, texwarp::PixelFormat::kUint16);
  const std::string common =
      "map-mesh --backend cpu --mesh " + dir + "/grid.glb --features " + dir + "/features.json --obj-uv warped";
  const std::string textures =
      " --texture color=" + kTexture + " --texture data=" + dir + "/rough.png --texture normal=" + dir + "/nrm.png";
  const CliRun set = run(common + textures + " --out-dir " + dir + "/maps --out-gltf " + dir + "/set.glb --report " +
                         dir + "/report.json");
  ASSERT_EQ(set.code, 0) << set.output;
  EXPECT_THAT(set.output, HasSubstr("wrote " + dir + "/maps/nrm.png (512×512, 4 channels, uint16); sampled as normal"));
  const std::array<std::pair<std::string, std::string>, 3> maps = {{{"color=" + kTexture, "astronaut.png"},
                                                                    {"data=" + dir + "/rough.png", "rough.png"},
                                                                    {"normal=" + dir + "/nrm.png", "nrm.png"}}};
  for (const auto& [input, name] : maps) {
    const std::string alone_file = std::string(dir).append("/alone-").append(name);
    std::string args = common;
    args.append(" --texture ").append(input).append(" --out-texture ").append(alone_file);
    const CliRun alone = run(args);
    ASSERT_EQ(alone.code, 0) << alone.output;
    const texwarp::Image a = texwarp::read_image(alone_file);
    const texwarp::Image b = texwarp::read_image(std::string(dir).append("/maps/").append(name));
    EXPECT_EQ(a.channels, b.channels) << name;
    EXPECT_TRUE(a.pixels == b.pixels) << name << ": the set's output differs from the map warped alone";
  }
  std::ifstream report_in(dir + "/report.json");
  const nlohmann::json report = nlohmann::json::parse(report_in);
  ASSERT_EQ(report.at("maps").size(), 3U);
  EXPECT_EQ(report.at("maps")[1].at("name"), "rough.png");
  EXPECT_EQ(report.at("maps")[1].at("output").at("sampling").at("role"), "data");
  EXPECT_EQ(report.at("maps")[2].at("output").at("sampling").at("role"), "normal");
  EXPECT_EQ(report.at("texture_sampling").at("role"), "color");
  std::ifstream glb_in(dir + "/set.glb", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(glb_in)), std::istreambuf_iterator<char>());
  const texwarp::mesh::GltfMesh back =
      texwarp::mesh::parse_gltf_mesh(bytes, true, {}, texwarp::proto::InputLocation::file("set.glb"));
  EXPECT_EQ(back.document.at("images").back().at("uri"), "maps/astronaut.png");

  // Refused, exit 2, naming the flag; the output folder is never made.
  texwarp::write_image(dir + "/small.png", texwarp::Image(256, 256, 3), texwarp::PixelFormat::kUint8);
  const std::string out = " --out-dir " + dir + "/bad";
  const std::array<std::pair<std::string, std::string>, 4> bad = {{
      {textures + " --out-texture " + dir + "/one.png",
       "--out-texture: 3 inputs (--texture) write one output each: give --out-dir"},
      {" --texture " + kTexture + " --texture " + dir + "/small.png" + out,
       "--texture: the maps of one warp share its pixels: " + dir + "/small.png is 256×256"},
      {" --texture '" + dir + "/t.<UDIM>.png'" + out,
       "names UDIM tiles: a mesh's warped texture is the region's frame"},
      {" --texture " + kTexture + " --texture " + dir + "/maps/astronaut.png" + out,
       "would both be written as astronaut.png in --out-dir"},
  }};
  for (const auto& [flags, message] : bad) {
    const CliRun r = run(common + flags);
    EXPECT_EQ(r.code, 2) << flags << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(message)) << flags;
  }
  EXPECT_FALSE(std::filesystem::exists(dir + "/bad"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/one.png"));

  // A second map with bytes of its image data garbled: with the IDAT chunk's CRC left as it was, refused when the
  // headers are read, before the mapping (exit 2 naming the file and the chunk); with the CRC made to match, its
  // header reads and its pixels do not, found when it is decoded after the first map: exit 2 naming it, no output
  // of the set and no output folder left (nested: the folders made for it are removed again).
  std::ifstream good(dir + "/rough.png", std::ios::binary);
  std::string png((std::istreambuf_iterator<char>(good)), std::istreambuf_iterator<char>());
  const auto chunk_length = [&](std::size_t at) {  // a chunk's big-endian length field at byte `at`
    std::size_t n = 0;
    for (std::size_t k = 0; k < 4; ++k) n = n << 8U | static_cast<unsigned char>(png[at + k]);
    return n;
  };
  std::size_t idat = 8;  // the first IDAT chunk: its length, type, data and CRC
  while (idat + 8 <= png.size() && png.compare(idat + 4, 4, "IDAT") != 0) idat += 12 + chunk_length(idat);
  ASSERT_LT(idat + 8, png.size());
  const std::size_t length = chunk_length(idat);
  ASSERT_GT(length, 4096U);
  for (std::size_t i = idat + 8 + length / 2; i < idat + 8 + length / 2 + 64; ++i) png[i] = static_cast<char>(~png[i]);
  write(dir, "broken.png", png);
  const std::string set_with = common + " --texture " + kTexture + " --texture data=" + dir + "/";
  const CliRun at_header = run(set_with + "broken.png --out-dir " + dir + "/made/maps");
  EXPECT_EQ(at_header.code, 2) << at_header.output;
  EXPECT_THAT(at_header.output, HasSubstr(dir + "/broken.png: is truncated or corrupt: the IDAT chunk at byte " +
                                          std::to_string(idat) + " fails its CRC check"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/made")) << at_header.output;
  const uLong crc =
      crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(png.data() + idat + 4), static_cast<uInt>(length + 4));
  for (int k = 0; k < 4; ++k) png[idat + 8 + length + k] = static_cast<char>((crc >> (24 - 8 * k)) & 0xFFU);
  write(dir, "garbled.png", png);
  ASSERT_EQ(texwarp::read_image_header(dir + "/garbled.png").width, 512);
  const CliRun broken = run(set_with + "garbled.png --out-dir " + dir + "/made/maps");
  EXPECT_EQ(broken.code, 2) << broken.output;
  EXPECT_THAT(broken.output, HasSubstr(dir + "/garbled.png"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/made")) << broken.output;
  std::filesystem::remove_all(dir);
}

// A quad mesh: the summary, the OBJ's comment and the report count its faces (quads) and triangles apart, and name
// input faces (each quad's two triangles the same face); with --refine, the faces of the OBJ written anew
// (triangles) and their source faces as input quads.
TEST(MapMeshCli, QuadMeshCountsFacesAndTrianglesApart) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  constexpr int kSide = 6;  // 6×6 quads on a gently curved sheet: 49 vertices, 36 faces, 72 triangles
  std::string obj;
  for (int j = 0; j <= kSide; ++j) {
    for (int i = 0; i <= kSide; ++i) {
      const double x = static_cast<double>(i) / kSide;
      obj += "v " + std::to_string(x) + " " + std::to_string(static_cast<double>(j) / kSide) + " " +
             std::to_string(0.1 * (x - 0.5) * (x - 0.5)) + "\n";
    }
  }
  for (int j = 0; j < kSide; ++j) {
    for (int i = 0; i < kSide; ++i) {
      const int a = j * (kSide + 1) + i + 1;
      obj += "f " + std::to_string(a) + " " + std::to_string(a + 1) + " " + std::to_string(a + kSide + 2) + " " +
             std::to_string(a + kSide + 1) + "\n";
    }
  }
  const std::string mesh = write(dir, "quads.obj", obj);
  const std::string features = write(dir, "quad_features.json", R"({"features": [
    {"source": [100, 100], "target": {"vertex": 8}}, {"source": [400, 120], "target": {"vertex": 12}},
    {"source": [250, 400], "target": {"vertex": 45}},
    {"source": [260, 250], "target": {"point": [0.41, 0.53, 0.00081]}}]})");
  const std::string args = "map-mesh --backend cpu --mesh " + mesh + " --texture " + kTexture + " --features " +
                           features + " --per-triangle";

  // The warp's own UVs (--optimize none): untangling would unfold the flips this test names.
  CliRun r = run(args + " --no-refine --optimize none --out-obj " + dir + "/q.obj --report " + dir + "/q.json");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("36 region faces (72 triangles), 4 features"));
  std::ifstream obj_file(dir + "/q.obj");
  std::string first_line;
  std::getline(obj_file, first_line);
  EXPECT_EQ(first_line, "# texwarp map-mesh: 36 region faces (72 triangles) textured, 4 features");
  nlohmann::json report = nlohmann::json::parse(std::ifstream(dir + "/q.json"));
  EXPECT_EQ(report.at("mesh"), (nlohmann::json{{"vertices", 49}, {"faces", 36}, {"triangles", 72}}));
  EXPECT_EQ(report.at("region").at("faces"), 36);
  EXPECT_EQ(report.at("region").at("triangles"), 72);
  std::vector<int> per_face(36, 0);
  for (const auto& t : report.at("triangles")) {
    const int face = t.at("face").get<int>();
    ASSERT_TRUE(face >= 0 && face < 36) << t.dump();
    ++per_face[face];
  }
  EXPECT_EQ(per_face, std::vector<int>(36, 2));
  ASSERT_FALSE(report.at("flips").empty()) << "the test wants flipped triangles to name";
  for (const auto& f : report.at("flips")) EXPECT_LT(f.at("face").get<int>(), 36) << f.dump();

  r = run(args + " --refine --optimize none --out-obj " + dir + "/r.obj --report " + dir + "/r.json");
  ASSERT_EQ(r.code, 0) << r.output;
  report = nlohmann::json::parse(std::ifstream(dir + "/r.json"));
  const int output_faces = report.at("refinement").at("output_faces").get<int>();
  EXPECT_GT(output_faces, 72);
  EXPECT_EQ(report.at("mesh").at("faces"), 36);
  EXPECT_EQ(report.at("region").at("faces"), output_faces);  // the whole sheet, in the OBJ written anew
  EXPECT_EQ(report.at("region").at("triangles"), output_faces);
  EXPECT_THAT(r.output, HasSubstr(std::to_string(output_faces) + " region faces, 4 features"));
  std::set<int> faces;
  for (const auto& t : report.at("triangles")) {
    faces.insert(t.at("face").get<int>());
    const int source = t.at("source_face").get<int>();
    EXPECT_TRUE(source >= 0 && source < 36) << t.dump();
  }
  EXPECT_EQ(static_cast<int>(faces.size()), output_faces);
  EXPECT_EQ(*faces.rbegin(), output_faces - 1);
  for (const auto& f : report.at("flips")) EXPECT_LT(f.at("source_face").get<int>(), 36) << f.dump();
  std::filesystem::remove_all(dir);
}

// An output that cannot be written fails the command before the mapping (exit 1, naming the flag), where the write
// itself failed after it with "cannot create a file in its folder".
TEST(MapMeshCli, AnOutputThatCannotBeWrittenFailsBeforeTheMapping) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  const std::string file = write(dir, "a_file", "not a folder");
  CliRun r = run(base_args() + " --out-obj " + dir + "/none/spot.obj");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output,
              HasSubstr("--out-obj " + dir + "/none/spot.obj: cannot write there (" + dir + "/none does not exist)"));
  r = run(base_args() + " --out-obj " + dir + "/spot.obj --report " + file + "/report.json");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output,
              HasSubstr("--report " + file + "/report.json: cannot write there (" + file + " is not a folder)"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/spot.obj"));
  r = run(base_args() + " --out-dir " + file + "/maps");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("--out-dir " + file + "/maps: cannot make the folder (Not a directory)"));
}

TEST(MapMeshCli, BadInputsExitWithCode2AndSayWhy) {
  const texwarp::testing::TestFolder folder{"map-mesh-cli"};
  const std::string dir = folder.path().string();
  const std::string features = kExamples + "spot_head_features.json";
  CliRun r = run("map-mesh --backend cpu --mesh " + kSpot + " --texture " + kTexture + " --features " + features);
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.output, HasSubstr(kSpot + ": the mesh is closed"));

  const std::string two = write(dir, "two.json", R"({"faces": [0, 3000]})");
  r = run("map-mesh --backend cpu --mesh " + kSpot + " --texture " + kTexture + " --features " + features +
          " --region " + two);
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.output, HasSubstr(two + ": the region is not a single disk: it has 2 connected components"));

  const std::string unknown =
      write(dir, "f.json", R"({"features": [{"source": [1, 2], "target": {"vertex": 7}, "oops": 1}]})");
  r = run(base_args().substr(0, base_args().find(" --features")) + " --features " + unknown + " --region " + kExamples +
          "spot_head_region.json");
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.output, HasSubstr(unknown + ": $.features[0].oops: unknown key"));

  const std::string outside = write(dir, "g.json", R"({"features": [{"source": [1, 2], "target": {"vertex": 0}}]})");
  r = run(base_args().substr(0, base_args().find(" --features")) + " --features " + outside + " --region " + kExamples +
          "spot_head_region.json");
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.output, HasSubstr(outside + ": $.features[0].target.vertex: vertex 0 is not in the region"));
  std::filesystem::remove_all(dir);
}

}  // namespace
