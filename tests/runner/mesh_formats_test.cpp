// Mesh jobs on every mesh format, run in-process: a glTF (.gltf and .glb) read, textured and written back, then read
// with tinygltf itself (positions unchanged, TEXCOORD_0 = uvs.json's UVs with glTF's top-left origin, the warped
// texture as the material's base colour), refined unless compressed; an OBJ of quads whose region and report speak of
// its input faces.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "gltf_accessors.hpp"
#include "gltf_test_files.hpp"
#include "mesh_test_shapes.hpp"
#include "test_folder.hpp"
#include "test_jobs.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/gltf_mesh.hpp"
#include "texwarp/mesh/tiny_gltf.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/runner/job_runner.hpp"

namespace texwarp::runner {
namespace {

namespace fs = std::filesystem;

// The texture through a scratch file; mesh paths relative to the scratch folder.
class FolderResolver final : public InputResolver {
 public:
  explicit FolderResolver(fs::path dir) : dir_(std::move(dir)) {}
  std::string image_file(const proto::ImageSourceSpec& image, const proto::JsonPath&) override {
    write_text_file_atomically((dir_ / "texture").string(), image.data);
    return (dir_ / "texture").string();
  }
  std::string mesh_file(const proto::MeshSourceSpec& source, const proto::JsonPath&) override {
    return (dir_ / source.path).string();
  }

 private:
  fs::path dir_;
};

class MeshFormatsTest : public ::testing::Test {
 protected:
  void SetUp() override { fs::create_directories(dir_ / "out"); }

  JobOutput run(const nlohmann::json& job) {
    spec_ = proto::decode_job_spec(job);
    FolderResolver inputs(dir_.path());
    return run_job(spec_, inputs, backends_, dir_ / "out", {}, {});
  }
  std::string out_file(const std::string& name) const {
    return read_text_file((dir_ / "out" / name).string(), 1 << 26);
  }

  texwarp::testing::TestFolder dir_{"mesh-formats"};
  proto::JobSpec spec_;
  BackendCache backends_{proto::DeviceSpec::cpu()};
};

// testing::mesh_job()'s 6×6 grid: the same vertex ids as mesh_test_shapes' flat_grid(6, 6).
nlohmann::json job_on(const std::string& path) {
  nlohmann::json job = testing::mesh_job();
  job["mesh"]["source"] = {{"path", path}};
  return job;
}

TEST_F(MeshFormatsTest, GltfRoundTripsThroughAJob) {
  const mesh::TriangleMesh grid = mesh::testing::flat_grid(6, 6);
  const mesh::testing::GltfParts parts = mesh::testing::gltf_parts(grid);
  for (const bool binary : {false, true}) {
    SCOPED_TRACE(binary ? "glb" : "gltf");
    const std::string input = binary ? mesh::testing::glb_bytes(parts) : mesh::testing::gltf_text(parts);
    const std::string name = binary ? "grid.glb" : "grid.gltf";
    write_text_file_atomically((dir_ / name).string(), input);
    nlohmann::json job = job_on(name);
    job["mesh"]["obj_uv"] = "warped";
    job["mesh"]["source"]["gltf"] = {{"mesh", "grid"}};
    const JobOutput out = run(job);
    const std::string result = binary ? kGlbFile : kGltfFile;
    ASSERT_EQ(out.files.at(0).name, result);
    EXPECT_EQ(out.files.at(0).media_type, binary ? "model/gltf-binary" : "model/gltf+json");
    const nlohmann::json uvs = nlohmann::json::parse(out_file(kUvFile));
    ASSERT_EQ(uvs.at("uv_origin"), "bottom_left");

    tinygltf::TinyGLTF loader;
    loader.SetImageLoader([](tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*,
                             int, void*) { return true; },
                          nullptr);
    tinygltf::Model model;
    std::string error, warning;
    const std::string bytes = out_file(result);
    ASSERT_TRUE(binary ? loader.LoadBinaryFromMemory(&model, &error, &warning,
                                                     reinterpret_cast<const unsigned char*>(bytes.data()),
                                                     static_cast<unsigned int>(bytes.size()))
                       : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(),
                                                    static_cast<unsigned int>(bytes.size()), ""))
        << error;
    const tinygltf::Primitive& p = model.meshes.at(0).primitives.at(0);
    const std::vector<float> positions = mesh::testing::accessor_floats(model, p.attributes.at("POSITION"));
    ASSERT_EQ(positions.size(), 3u * grid.vertices.size());
    for (std::size_t v = 0; v < grid.vertices.size(); ++v) {
      EXPECT_EQ(positions[3 * v], static_cast<float>(grid.vertices[v].x));
      EXPECT_EQ(positions[3 * v + 1], static_cast<float>(grid.vertices[v].y));
    }
    // The whole grid is the region: every glTF vertex has uvs.json's warped UV, v flipped to the top-left origin.
    const std::vector<float> texcoord = mesh::testing::accessor_floats(model, p.attributes.at("TEXCOORD_0"));
    const auto& vertices = uvs.at("vertices");
    ASSERT_EQ(vertices.size(), grid.vertices.size());
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      const int v = vertices[i].get<int>();
      const double u = uvs.at("warped_uv")[i][0].get<double>();
      const double w = uvs.at("warped_uv")[i][1].get<double>();
      const std::size_t at = std::size_t{2} * static_cast<std::size_t>(v);
      EXPECT_FLOAT_EQ(texcoord[at], static_cast<float>(u));
      EXPECT_NEAR(texcoord[at + 1], 1.0 - w, 1e-6);
    }
    const tinygltf::Material& material = model.materials.at(p.material);
    const int texture = material.pbrMetallicRoughness.baseColorTexture.index;
    ASSERT_GE(texture, 0);
    EXPECT_EQ(model.images.at(model.textures.at(texture).source).uri, "warped.png");
    std::vector<float> second(2 * grid.vertices.size(), 0.25F);
    for (std::size_t i = 1; i < second.size(); i += 2) second[i] = 0.75F;
    EXPECT_EQ(mesh::testing::accessor_floats(model, p.attributes.at("TEXCOORD_1")),
              second);  // other attributes as they were
  }
}

// A glTF job is refined by default: a feature inside face 24 becomes a vertex, written into the glTF with its position
// interpolated on the face. A primitive whose vertex data is compressed keeps its faces, and asking to refine it is
// refused at options.refine, nothing written.
TEST_F(MeshFormatsTest, AGltfPrimitiveIsRefinedUnlessItsVertexDataIsCompressed) {
  const mesh::TriangleMesh grid = mesh::testing::flat_grid(6, 6);
  mesh::testing::GltfParts parts = mesh::testing::gltf_parts(grid);
  write_text_file_atomically((dir_ / "grid.glb").string(), mesh::testing::glb_bytes(parts));
  nlohmann::json job = job_on("grid.glb");
  job["mesh"]["features"]["features"].push_back(
      {{"id", "inside"}, {"source", {10, 35}}, {"target", {{"face", 24}, {"barycentric", {0.2, 0.3, 0.5}}}}});
  const JobOutput out = run(job);
  ASSERT_TRUE(out.report.mesh && out.report.mesh->refinement);
  EXPECT_EQ(out.report.mesh->refinement->feature_vertices, 1);
  const mesh::GltfMesh back = mesh::parse_gltf_mesh(out_file(kGlbFile), true, {}, proto::InputLocation::file(kGlbFile));
  EXPECT_EQ(back.mesh.face_count(), out.report.mesh->refinement->output_faces);
  ASSERT_EQ(back.mesh.vertex_count(), grid.vertex_count() + out.report.mesh->refinement->added_vertices);
  const mesh::Vec3 inside =
      mesh::interpolate(grid.corner(24, 0), grid.corner(24, 1), grid.corner(24, 2), {0.2, 0.3, 0.5});
  const mesh::Vec3 added = back.mesh.vertices.at(static_cast<std::size_t>(grid.vertex_count()));
  EXPECT_NEAR(added.x, inside.x, 1e-6);
  EXPECT_NEAR(added.y, inside.y, 1e-6);

  parts.json["extensionsUsed"] = {"EXT_meshopt_compression"};
  const int normal = parts.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"].get<int>();
  parts.json["bufferViews"][parts.json["accessors"][normal]["bufferView"].get<int>()]["extensions"] = {
      {"EXT_meshopt_compression", {{"buffer", 0}, {"mode", "ATTRIBUTES"}}}};
  write_text_file_atomically((dir_ / "packed.glb").string(), mesh::testing::glb_bytes(parts));
  nlohmann::json packed = job_on("packed.glb");
  packed["mesh"]["features"] = job["mesh"]["features"];
  fs::remove_all(dir_ / "out");
  fs::create_directories(dir_ / "out");
  const JobOutput kept = run(packed);
  ASSERT_TRUE(kept.report.mesh);
  EXPECT_FALSE(kept.report.mesh->refinement);
  EXPECT_EQ(mesh::parse_gltf_mesh(out_file(kGlbFile), true, {}, proto::InputLocation::file(kGlbFile)).mesh.faces,
            grid.faces);
  fs::remove_all(dir_ / "out");
  fs::create_directories(dir_ / "out");
  packed["options"] = {{"refine", true}};
  std::string message;
  try {
    run(packed);
  } catch (const InputError& e) {
    message = e.what();
  }
  EXPECT_EQ(message, "$.options.refine: this glTF primitive cannot take new vertices: its vertex data is compressed "
                     "(EXT_meshopt_compression)");
  EXPECT_TRUE(fs::is_empty(dir_ / "out"));
}

TEST_F(MeshFormatsTest, HostileGltfIsRefusedAtTheMeshSource) {
  mesh::testing::GltfParts parts = mesh::testing::gltf_parts(mesh::testing::flat_grid(2, 2));
  parts.json["meshes"][0]["primitives"][0]["mode"] = 1;
  write_text_file_atomically((dir_ / "lines.gltf").string(), mesh::testing::gltf_text(parts));
  std::string message;
  try {
    run(job_on("lines.gltf"));
  } catch (const InputError& e) {
    message = e.what();
  }
  EXPECT_EQ(message, "$.mesh.source: mesh 0 (\"grid\") primitive 0: mode 1 is not triangles (4): points, lines, "
                     "strips and fans are not read");
  EXPECT_TRUE(fs::is_empty(dir_ / "out"));
}

TEST_F(MeshFormatsTest, QuadObjRegionAndReportNameInputFaces) {
  // The 6×6 grid as 36 quads: quad q = j·6 + i on vertices (i, j), (i+1, j), (i+1, j+1), (i, j+1).
  std::string obj = "# quads\nmtllib grid.mtl\nusemtl skin\n";
  for (int j = 0; j <= 6; ++j) {
    for (int i = 0; i <= 6; ++i) obj += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
  }
  obj += "vn 0 0 1\n";
  for (int j = 0; j < 6; ++j) {
    for (int i = 0; i < 6; ++i) {
      const int a = j * 7 + i + 1;
      obj += "f " + std::to_string(a) + "//1 " + std::to_string(a + 1) + "//1 " + std::to_string(a + 8) + "//1 " +
             std::to_string(a + 7) + "//1\n";
    }
  }
  nlohmann::json job = testing::mesh_job();
  job["mesh"]["source"] = {{"obj", obj}};
  nlohmann::json faces = nlohmann::json::array();
  for (int q = 0; q < 36; ++q) faces.push_back(q);
  job["mesh"]["region"] = {{"faces", faces}};
  job["mesh"]["per_triangle"] = true;
  const JobOutput out = run(job);
  ASSERT_TRUE(out.report.mesh && out.report.mesh->triangles);
  const auto& triangles = *out.report.mesh->triangles;
  ASSERT_EQ(triangles.size(), 72u);
  for (std::size_t t = 0; t < triangles.size(); ++t) EXPECT_EQ(triangles[t].face, static_cast<int>(t / 2));
  EXPECT_EQ(out.report.mesh->uvs.flipped_triangles, 0);
  // mesh.obj: the input's lines, the quads now with vt (v and vn as written), the new vt lines at the end.
  const std::string text = out_file(kObjFile);
  EXPECT_NE(text.find("\nmtllib grid.mtl\nusemtl skin\n"), std::string::npos);
  EXPECT_NE(text.find("\nf 1/1/1 2/2/1 9/9/1 8/8/1\n"), std::string::npos);
  EXPECT_NE(text.find("\nvn 0 0 1\n"), std::string::npos);
}

// A sheet of `columns` × `rows` faces on z = 0.1·(x − 0.5)², as OBJ text; each face spans `cells` grid cells across
// (1: quads; 2: hexagons, their mid-edge vertices shared with the faces above and below).
std::string polygon_sheet_obj(int columns, int rows, int cells) {
  const int nx = columns * cells + 1;
  std::ostringstream obj;
  obj.precision(17);
  for (int j = 0; j <= rows; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double x = static_cast<double>(i) / (nx - 1);
      obj << "v " << x << " " << static_cast<double>(j) / rows << " " << 0.1 * (x - 0.5) * (x - 0.5) << "\n";
    }
  }
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      obj << "f";
      for (int k = 0; k <= cells; ++k) obj << " " << r * nx + c * cells + k + 1;
      for (int k = cells; k >= 0; --k) obj << " " << (r + 1) * nx + c * cells + k + 1;
      obj << "\n";
    }
  }
  return obj.str();
}

// An OBJ text's `v` positions and `f` lines (0-based ids), read here (not by texwarp's reader).
struct ObjLines {
  std::vector<std::array<double, 3>> v;
  std::vector<std::vector<int>> f;
};

ObjLines obj_lines(const std::string& text) {
  ObjLines out;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream in(line);
    std::string tag;
    in >> tag;
    if (tag == "v") {
      std::array<double, 3> p{};
      in >> p[0] >> p[1] >> p[2];
      out.v.push_back(p);
    } else if (tag == "f") {
      out.f.emplace_back();
      for (std::string token; in >> token;) out.f.back().push_back(std::stoi(token.substr(0, token.find('/'))) - 1);
    }
  }
  return out;
}

// uvs.json's new_vertices of a refined quad and hexagon OBJ: each names its file face and the three file vertices
// (of that face's f line) its weights are on; the weights over those corners give the vertex's position in the
// written mesh.obj, to 1e-9.
TEST_F(MeshFormatsTest, RefinedPolygonObjNamesTheCornersOfEachAddedVertex) {
  for (const int cells : {1, 2}) {
    SCOPED_TRACE(cells == 1 ? "quads" : "hexagons");
    const std::string obj = polygon_sheet_obj(6 / cells, 6, cells);
    const ObjLines in = obj_lines(obj);
    nlohmann::json job = testing::mesh_job();
    job["mesh"]["source"] = {{"obj", obj}};
    // Point targets inside faces (refine makes each a vertex), sources near the sheet's own layout on the 64² image.
    nlohmann::json features = nlohmann::json::array();
    const std::vector<std::array<double, 2>> points = {{0.08, 0.11}, {0.61, 0.14}, {0.37, 0.45},
                                                       {0.88, 0.55}, {0.22, 0.79}, {0.71, 0.93}};
    for (std::size_t k = 0; k < points.size(); ++k) {
      const auto [x, y] = points[k];
      const double dx = k % 2 == 0 ? 1.5 : -1.0, dy = k % 3 == 0 ? -1.0 : 1.2;
      features.push_back({{"source", {8.0 + 48.0 * x + dx, 56.0 - 48.0 * y + dy}},
                          {"target", {{"point", {x, y, 0.1 * (x - 0.5) * (x - 0.5)}}}}});
    }
    job["mesh"]["features"]["features"] = features;
    job["options"] = {{"refine", true}};
    fs::remove_all(dir_ / "out");
    fs::create_directories(dir_ / "out");
    const JobOutput out = run(job);
    ASSERT_TRUE(out.report.mesh && out.report.mesh->refinement);
    const nlohmann::json uvs = nlohmann::json::parse(out_file(kUvFile));
    const ObjLines written = obj_lines(out_file(kObjFile));
    const int first = uvs.at("new_vertices").at("first").get<int>();
    EXPECT_EQ(first, static_cast<int>(in.v.size()));
    const nlohmann::json& added = uvs.at("new_vertices").at("source");
    ASSERT_GE(added.size(), points.size());
    ASSERT_EQ(written.v.size(), in.v.size() + added.size());
    for (std::size_t k = 0; k < added.size(); ++k) {
      const int face = added[k].at("face").get<int>();
      const auto w = added[k].at("barycentric").get<std::array<double, 3>>();
      const auto corners = added[k].at("corners").get<std::array<int, 3>>();
      const std::vector<int>& f_line = in.f.at(static_cast<std::size_t>(face));
      std::array<double, 3> q{};
      for (int c = 0; c < 3; ++c) {
        EXPECT_NE(std::find(f_line.begin(), f_line.end(), corners[c]), f_line.end())
            << "new vertex " << k << ": corner " << corners[c] << " is not on f line " << face;
        for (int d = 0; d < 3; ++d) q[d] += w[c] * in.v.at(static_cast<std::size_t>(corners[c]))[d];
      }
      const std::array<double, 3>& p = written.v[static_cast<std::size_t>(first) + k];
      for (int d = 0; d < 3; ++d) EXPECT_NEAR(q[d], p[d], 1e-9) << "new vertex " << k << " coordinate " << d;
    }
  }
}

}  // namespace
}  // namespace texwarp::runner
