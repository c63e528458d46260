// Regions: the disk check says why a region is not a disk (components, pinch, closed, genus, holes); face
// sets and closed curves + seed faces select the expected faces; the region file decoder is strict.
#include <algorithm>
#include <map>
#include <set>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "input_error_text.hpp"
#include "mesh_test_shapes.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/edge_key.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/region_spec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"

namespace texwarp::mesh {
namespace {

using texwarp::testing::input_error_of;

using ::testing::HasSubstr;

const std::string kSpot = std::string(TEXWARP_SOURCE_DIR) + "/examples/mesh/spot.obj";
const std::string kHeadRegion = std::string(TEXWARP_SOURCE_DIR) + "/examples/mesh/spot_head_region.json";

std::vector<int> all_faces(const TriangleMesh& m) {
  std::vector<int> f(static_cast<std::size_t>(m.face_count()));
  for (int i = 0; i < m.face_count(); ++i) f[i] = i;
  return f;
}

RegionSpec spec_of(const std::string& text) { return proto::decode_region_spec(proto::parse_json(text, "region")); }

TEST(DiskRegion, WholeGridIsADiskWithItsPerimeterAsBoundary) {
  const TriangleMesh grid = testing::flat_grid(6, 4);
  const MeshRegion r = whole_mesh_region(grid, proto::InputLocation::file("grid"));
  EXPECT_EQ(r.face_count(), 48);
  EXPECT_EQ(r.vertex_count(), 35);
  EXPECT_EQ(r.boundary.size(), 2u * (6 + 4));
  // Every boundary vertex lies on the grid's outline, and the loop follows the faces' (counter-clockwise)
  // orientation: its signed area is positive.
  double area2 = 0.0;
  for (std::size_t i = 0; i < r.boundary.size(); ++i) {
    const Vec3 a = r.local.vertices[r.boundary[i]];
    const Vec3 b = r.local.vertices[r.boundary[(i + 1) % r.boundary.size()]];
    EXPECT_TRUE(a.x == 0 || a.x == 6 || a.y == 0 || a.y == 4);
    area2 += a.x * b.y - a.y * b.x;
  }
  EXPECT_DOUBLE_EQ(0.5 * area2, 24.0);
}

TEST(DiskRegion, ClosedSurfaceIsRefused) {
  EXPECT_THAT(
      input_error_of([] { whole_mesh_region(testing::octahedron(), proto::InputLocation::file("oct.obj")); }),
      HasSubstr("oct.obj: the mesh is closed (no boundary; genus 0, Euler characteristic V − E + F = 6 − 12 + 8 = 2)"));
  const TriangleMesh spot = read_mesh_file(kSpot);
  EXPECT_THAT(input_error_of([&] { whole_mesh_region(spot, proto::InputLocation::file("spot.obj")); }),
              HasSubstr("the mesh is closed"));
  EXPECT_THAT(input_error_of([] { whole_mesh_region(testing::torus(2, 0.5, 10, 6), proto::InputLocation::file("t")); }),
              HasSubstr("is closed (no boundary; genus 1"));
}

TEST(DiskRegion, SeveralComponentsAreRefused) {
  TriangleMesh m = testing::flat_grid(2, 1);
  const TriangleMesh other = testing::flat_grid(1, 1);
  const int base = m.vertex_count();
  for (Vec3 v : other.vertices) m.vertices.push_back({v.x + 10, v.y, v.z});
  for (Face f : other.faces) m.faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  EXPECT_THAT(
      input_error_of([&] { whole_mesh_region(m, proto::InputLocation::file("m")); }),
      HasSubstr(
          "the mesh is not a single disk: it has 2 connected components (4 faces from face 0; 2 faces from face 4)"));
}

TEST(DiskRegion, PinchedVertexIsRefused) {
  // A 3×3 grid without its centre cell (1, 1) and the corner cell (2, 0): still one component (around the
  // ring), but cells (1, 0) and (2, 1) meet at vertex (2, 1) = 6 only, where its faces form two fans.
  const TriangleMesh m = testing::flat_grid(3, 3);
  std::vector<int> faces;
  for (int cell = 0; cell < 9; ++cell) {
    const int i = cell % 3, j = cell / 3;
    if ((i == 1 && j == 1) || (i == 2 && j == 0)) continue;
    faces.push_back(2 * cell);
    faces.push_back(2 * cell + 1);
  }
  EXPECT_THAT(input_error_of([&] { disk_region(m, faces, proto::InputLocation::file("r.json")); }),
              HasSubstr("r.json: the region is not a disk: it touches itself at 1 vertex (6)"));
}

TEST(DiskRegion, HolesAreRefused) {
  EXPECT_THAT(input_error_of([] { whole_mesh_region(testing::annulus(1, 2, 16), proto::InputLocation::file("ring")); }),
              HasSubstr("the mesh is not a disk: it has 2 boundary loops (16 vertices from vertex 0; 16 vertices from "
                        "vertex 1), i.e. 1 hole"));
  const TriangleMesh grid = testing::flat_grid(5, 5);
  std::vector<int> faces;
  for (int f = 0; f < grid.face_count(); ++f) {
    const int cell = f / 2;
    if (cell != 6 && cell != 18) faces.push_back(f);  // two interior cells removed: two holes
  }
  EXPECT_THAT(input_error_of([&] { disk_region(grid, faces, proto::InputLocation::file("r")); }),
              HasSubstr("3 boundary loops"));
  EXPECT_THAT(input_error_of([&] { disk_region(grid, faces, proto::InputLocation::file("r")); }),
              HasSubstr("i.e. 2 holes"));
}

TEST(DiskRegion, GenusIsRefused) {
  TriangleMesh t = testing::torus(2, 0.5, 10, 6);
  std::vector<int> faces = all_faces(t);
  faces.erase(faces.begin() + 7);  // one boundary loop, genus 1
  EXPECT_THAT(input_error_of([&] { disk_region(t, faces, proto::InputLocation::file("r")); }),
              HasSubstr("the region is not a disk: it has genus 1 (Euler characteristic V − E + F = 60 − 180 + 119 = "
                        "-1, 1 boundary loop"));
}

TEST(DiskRegion, EmptyRegionIsRefused) {
  EXPECT_THAT(input_error_of([] { disk_region(testing::flat_grid(1, 1), {}, proto::InputLocation::file("r")); }),
              HasSubstr("the region has no faces"));
}

TEST(RegionSpecCodec, DecodesBothForms) {
  const RegionSpec faces = spec_of(R"({"faces": [3, 1, 2]})");
  EXPECT_FALSE(faces.is_curve());
  EXPECT_EQ(faces.faces, (std::vector<int>{3, 1, 2}));
  const RegionSpec curve = spec_of(R"({"boundary": [5, 6, 7], "seed_face": 4})");
  EXPECT_TRUE(curve.is_curve());
  EXPECT_EQ(curve.boundary, (std::vector<int>{5, 6, 7}));
  EXPECT_EQ(curve.seed_face, 4);
}

TEST(RegionSpecCodec, ErrorsNameTheJsonPath) {
  EXPECT_THAT(input_error_of([] { spec_of(R"({"faces": [1, 2, 1]})"); }),
              HasSubstr("$.faces[2]: face 1 is listed twice"));
  EXPECT_THAT(input_error_of([] { spec_of(R"({"faces": [1, 2], "boundary": [1]})"); }), HasSubstr("not both"));
  EXPECT_THAT(input_error_of([] { spec_of(R"({})"); }), HasSubstr("expected \"faces\""));
  EXPECT_THAT(input_error_of([] { spec_of(R"({"boundary": [1, 2, 3]})"); }),
              HasSubstr("$.seed_face: required key is missing"));
  EXPECT_THAT(input_error_of([] { spec_of(R"({"faces": [1, -2]})"); }), HasSubstr("$.faces[1]: id -2 is out of range"));
  EXPECT_THAT(input_error_of([] { spec_of(R"({"faces": [1, 2.5]})"); }), HasSubstr("$.faces[1]: expected an id"));
  EXPECT_THAT(input_error_of([] { spec_of(R"({"faces": [1], "name": "x"})"); }), HasSubstr("$.name: unknown key"));
  EXPECT_THAT(input_error_of([] { spec_of(R"({"faces": []})"); }), HasSubstr("$.faces: the face list is empty"));
}

TEST(RegionSelection, IdsOutOfRangeNameTheJsonPath) {
  const TriangleMesh grid = testing::flat_grid(2, 2);
  EXPECT_THAT(input_error_of(
                  [&] { select_region(grid, spec_of(R"({"faces": [0, 8]})"), proto::InputLocation::file("r.json")); }),
              HasSubstr("r.json: $.faces[1]: face 8 does not exist (the mesh has 8 faces)"));
  EXPECT_THAT(input_error_of([&] {
                select_region(grid, spec_of(R"({"boundary": [0, 1, 90], "seed_face": 0})"),
                              proto::InputLocation::file("r.json"));
              }),
              HasSubstr("r.json: $.boundary[2]: vertex 90 does not exist"));
  EXPECT_THAT(input_error_of([&] {
                select_region(grid, spec_of(R"({"boundary": [0, 1, 4], "seed_face": 9})"),
                              proto::InputLocation::file("r.json"));
              }),
              HasSubstr("r.json: $.seed_face: face 9 does not exist"));
}

TEST(RegionSelection, CurveCornersAreJoinedByShortestPathsAndTheInsideIsFilled) {
  // 8×8 grid; the curve gives the four corners of the vertex rectangle [2, 6] × [1, 5]: joined along grid
  // lines (the straight row or column is the unique shortest edge path), the inside holds 4·4 cells.
  const TriangleMesh grid = testing::flat_grid(8, 8);
  auto id = [](int i, int j) { return j * 9 + i; };
  const std::string text = "{\"boundary\": [" + std::to_string(id(2, 1)) + ", " + std::to_string(id(6, 1)) + ", " +
                           std::to_string(id(6, 5)) + ", " + std::to_string(id(2, 5)) +
                           "], \"seed_face\": " + std::to_string(2 * (3 * 8 + 4)) + "}";
  const MeshRegion r = select_region(grid, spec_of(text), proto::InputLocation::file("r"));
  ASSERT_EQ(r.face_count(), 32);
  for (int f : r.faces) {
    const int cell = f / 2;
    const int i = cell % 8, j = cell / 8;
    EXPECT_TRUE(i >= 2 && i < 6 && j >= 1 && j < 5) << "face " << f;
  }
  EXPECT_EQ(r.boundary.size(), 16u);
  // From a seed outside the curve: the grid minus the rectangle, an annulus: refused as a disk with a hole.
  const std::string outside = text.substr(0, text.find("\"seed_face\"")) + "\"seed_face\": 0}";
  EXPECT_THAT(input_error_of([&] { select_region(grid, spec_of(outside), proto::InputLocation::file("r")); }),
              HasSubstr("i.e. 1 hole"));
}

TEST(RegionSelection, CurveMustBeSimpleAndSeparating) {
  const TriangleMesh grid = testing::flat_grid(4, 4);
  // 0 → 1 → 2 → 7 → 1 → ...: back at vertex 1.
  EXPECT_THAT(input_error_of([&] {
                select_region(grid, spec_of(R"({"boundary": [0, 1, 2, 7, 1, 5], "seed_face": 0})"),
                              proto::InputLocation::file("r"));
              }),
              HasSubstr("passes vertex 1 twice"));
  EXPECT_THAT(input_error_of([&] {
                select_region(grid, spec_of(R"({"boundary": [0, 1, 0], "seed_face": 0})"),
                              proto::InputLocation::file("r"));
              }),
              HasSubstr("at least 3 distinct vertices"));
  // A meridian of a torus is a simple closed curve that does not separate it.
  const TriangleMesh t = testing::torus(2, 0.5, 10, 6);
  EXPECT_THAT(input_error_of([&] {
                select_region(t, spec_of(R"({"boundary": [0, 1, 2, 3, 4, 5], "seed_face": 30})"),
                              proto::InputLocation::file("r"));
              }),
              HasSubstr("the boundary curve does not separate the surface"));
}

TEST(RegionSelection, SpotHeadCurveGivesADisk) {
  const TriangleMesh spot = read_mesh_file(kSpot);
  const RegionSpec spec =
      proto::decode_region_spec(proto::parse_json(read_text_file(kHeadRegion, 1 << 20), kHeadRegion));
  const MeshRegion r = select_region(spot, spec, proto::InputLocation::file(kHeadRegion));
  EXPECT_EQ(r.face_count(), 1800);
  EXPECT_EQ(r.vertex_count(), 933);
  // Independent check: count the region's edges by hand: χ = V − E + F = 1, and every boundary edge (used by
  // one region face) joins two vertices of the closed curve.
  const std::vector<int> curve = close_vertex_curve(spot, spec.boundary, proto::InputLocation::file("r"));
  const std::set<int> on_curve(curve.begin(), curve.end());
  std::map<EdgeKey, int> uses;
  for (int f : r.faces) {
    for (int k = 0; k < 3; ++k) ++uses[edge_key(spot.faces[f][k], spot.faces[f][(k + 1) % 3])];
  }
  EXPECT_EQ(r.vertex_count() - static_cast<int>(uses.size()) + r.face_count(), 1);
  int boundary_edges = 0;
  for (const auto& [key, count] : uses) {
    if (count == 1) {
      ++boundary_edges;
      const auto [a, b] = edge_vertices(key);
      EXPECT_TRUE(on_curve.count(a) && on_curve.count(b));
    }
  }
  EXPECT_EQ(boundary_edges, static_cast<int>(curve.size()));
  EXPECT_EQ(r.boundary.size(), curve.size());
  // The seed face is inside, and the region is the head: z > 0.45 for every vertex.
  EXPECT_GE(r.local_face[spec.seed_face], 0);
  for (const Vec3& v : r.local.vertices) EXPECT_GT(v.z, 0.45);
}

}  // namespace
}  // namespace texwarp::mesh
