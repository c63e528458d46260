// Mesh input: OBJ through tinyobjloader (ids as in the file, quads triangulated), the inline JSON form (strict,
// JSON paths), file reading with validation, and the textured OBJ read back.
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "input_error_text.hpp"
#include "test_folder.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/obj_output.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"

namespace texwarp::mesh {
namespace {

using texwarp::testing::input_error_of;

using ::testing::HasSubstr;

const std::string kSpot = std::string(TEXWARP_SOURCE_DIR) + "/examples/mesh/spot.obj";

// A file in the test's own folder (removed when the test passes; a fixed name in /tmp stayed after every run).
std::string temp_file(const std::string& name, const std::string& text) {
  const auto path = texwarp::testing::test_folder_path("mesh-input") / name;
  std::ofstream(path) << text;
  return path.string();
}

TEST(ObjInput, FacesKeepTheFileOrderAcrossGroups) {
  const std::string obj = "# two groups, texture coordinates and normals that are ignored\n"
                          "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\n"
                          "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
                          "g first\nf 1/1/1 2/2/1 3/3/1\n"
                          "g second\nf 1 3 4\nf -5 -4 -1\n";
  const TriangleMesh m = parse_obj_mesh(obj, proto::InputLocation::file("t.obj"));
  ASSERT_EQ(m.vertex_count(), 5);
  ASSERT_EQ(m.face_count(), 3);
  EXPECT_EQ(m.faces[0], (Face{0, 1, 2}));
  EXPECT_EQ(m.faces[1], (Face{0, 2, 3}));
  EXPECT_EQ(m.faces[2], (Face{0, 1, 4}));  // relative indices resolved
  EXPECT_DOUBLE_EQ(m.vertices[4].x, 0.5);
  EXPECT_DOUBLE_EQ(m.vertices[4].z, 1.0);
}

TEST(ObjInput, CoordinatesAreReadInDoublePrecision) {
  const TriangleMesh m =
      parse_obj_mesh("v 0.1234567890123 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", proto::InputLocation::file("t.obj"));
  EXPECT_EQ(m.vertices[0].x, 0.1234567890123);
}

TEST(ObjInput, QuadsAreTriangulatedAndKeepTheirFaceId) {
  const MeshFile file =
      parse_obj_file("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 2 3 4\n", proto::InputLocation::file("q.obj"));
  EXPECT_EQ(file.mesh.faces, (std::vector<Face>{{0, 1, 2}, {0, 1, 2}, {0, 2, 3}}));  // a convex quad: a fan
  EXPECT_EQ(file.faces.of_triangle, (std::vector<int>{0, 1, 1}));
}

TEST(ObjInput, ReadsAndValidatesSpot) {
  const TriangleMesh m = read_mesh_file(kSpot);
  EXPECT_EQ(m.vertex_count(), 2930);
  EXPECT_EQ(m.face_count(), 5856);
}

TEST(ObjInput, FileErrorsNameTheFile) {
  EXPECT_THAT(input_error_of([] { read_mesh_file("/nonexistent/mesh.obj"); }),
              HasSubstr("/nonexistent/mesh.obj: cannot open"));
  EXPECT_THAT(input_error_of([] { read_mesh_file("mesh.ply"); }), HasSubstr("unknown mesh format"));
  const std::string bad = temp_file("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
  EXPECT_THAT(input_error_of([&] { read_mesh_file(bad); }), HasSubstr(bad));
  const std::string lonely = temp_file("lonely.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 3 3 3\nf 1 2 3\n");
  EXPECT_THAT(input_error_of([&] { read_mesh_file(lonely); }),
              HasSubstr(lonely + ": vertex 3 is not used by any face"));
}

TEST(JsonInput, DecodesVerticesAndTriangles) {
  const auto j = proto::parse_json(R"({"vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1,2]]})", "t");
  const TriangleMesh m = mesh_from_spec(proto::decode_mesh_data(j));
  ASSERT_EQ(m.vertex_count(), 3);
  EXPECT_EQ(m.faces.at(0), (Face{0, 1, 2}));
  EXPECT_DOUBLE_EQ(m.vertices[2].y, 1.0);
}

TEST(JsonInput, ErrorsNameTheJsonPath) {
  auto error = [](const char* text) {
    return input_error_of([&] { mesh_from_spec(proto::decode_mesh_data(proto::parse_json(text, "t"))); });
  };
  EXPECT_THAT(error(R"({"vertices": [[0,0,0]], "triangles": [], "colors": []})"), HasSubstr("$.colors: unknown key"));
  EXPECT_THAT(error(R"({"vertices": [[0,0]], "triangles": []})"),
              HasSubstr("$.vertices[0]: expected a point [x, y, z]"));
  EXPECT_THAT(error(R"({"vertices": [[0,0,"a"]], "triangles": []})"), HasSubstr("$.vertices[0][2]: expected a number"));
  EXPECT_THAT(error(R"({"vertices": [], "triangles": [[0,1,2.5]]})"),
              HasSubstr("$.triangles[0][2]: expected a vertex index"));
  EXPECT_THAT(error(R"({"vertices": [], "triangles": [[0,1,-2]]})"), HasSubstr("$.triangles[0][2]: vertex index -2"));
  EXPECT_THAT(error(R"({"vertices": []})"), HasSubstr("$.triangles: required key is missing"));
}

TEST(JsonInput, FileIsValidatedWithJsonPaths) {
  const std::string path =
      temp_file("dup.json", R"({"vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1,2],[1,2,0]]})");
  EXPECT_THAT(input_error_of([&] { read_mesh_file(path); }),
              HasSubstr("$.triangles[0] and $.triangles[1] are duplicates"));
}

TEST(ObjOutput, KeepsVerticesAndFacesAndAddsRegionUvs) {
  const TriangleMesh mesh = read_mesh_file(kSpot);
  // A region of a few faces around face 0 (a disk: face 0 and its neighbours).
  const MeshRegion region = disk_region(mesh, {0}, proto::InputLocation::file("test"));
  std::vector<std::array<double, 2>> uvs = {{0.25, 0.5}, {0.75, 0.5}, {0.5, 0.125}};
  const std::string text = textured_obj_text(mesh, region, uvs, "a comment\nsecond line");
  EXPECT_EQ(text.rfind("# a comment\n# second line\n", 0), 0u);
  const TriangleMesh back = parse_obj_mesh(text, proto::InputLocation::file("back.obj"));
  ASSERT_EQ(back.vertex_count(), mesh.vertex_count());
  ASSERT_EQ(back.face_count(), mesh.face_count());
  EXPECT_EQ(back.faces, mesh.faces);
  // The v lines hold the shortest text that strtod reads back to the same double (tinyobjloader's own
  // number parser may differ from strtod in the last bit).
  std::istringstream lines(text);
  int v = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("v ", 0) != 0) continue;
    char* end = nullptr;
    const double x = std::strtod(line.c_str() + 2, &end);
    const double y = std::strtod(end, &end);
    const double z = std::strtod(end, &end);
    ASSERT_EQ(x, mesh.vertices[v].x);
    ASSERT_EQ(y, mesh.vertices[v].y);
    ASSERT_EQ(z, mesh.vertices[v].z);
    EXPECT_NEAR(back.vertices[v].x, x, 1e-15);
    ++v;
  }
  EXPECT_EQ(v, mesh.vertex_count());
  const Face& f0 = mesh.faces[0];
  char line[96];
  std::snprintf(line, sizeof line, "\nf %d/%d %d/%d %d/%d\n", f0[0] + 1, region.local_vertex[f0[0]] + 1, f0[1] + 1,
                region.local_vertex[f0[1]] + 1, f0[2] + 1, region.local_vertex[f0[2]] + 1);
  EXPECT_THAT(text, HasSubstr(line));
  EXPECT_THAT(text, HasSubstr("\nvt 0.25 0.5\nvt 0.75 0.5\nvt 0.5 0.125\nf "));
}

}  // namespace
}  // namespace texwarp::mesh
