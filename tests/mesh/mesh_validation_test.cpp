// Mesh validation: every defect gives its own InputError naming the face or vertex; valid meshes pass.
#include <cmath>
#include <limits>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mesh_test_shapes.hpp"
#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {
namespace {

using ::testing::HasSubstr;

std::string error_of(const TriangleMesh& mesh, const MeshSource& source = {proto::InputLocation::file("m.obj"), {}}) {
  try {
    validate_mesh(mesh, source);
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), source.where);
    return e.detail();
  }
  return "";
}

TriangleMesh two_triangles() {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(MeshValidation, ValidMeshesPass) {
  EXPECT_EQ(error_of(two_triangles()), "");
  EXPECT_EQ(error_of(testing::flat_grid(5, 4, 1.0, 0.2)), "");
  EXPECT_EQ(error_of(testing::torus(2.0, 0.5, 12, 8)), "");
  EXPECT_EQ(error_of(testing::octahedron()), "");
  EXPECT_EQ(error_of(testing::sphere_cap(1.2, 6, 12)), "");
}

TEST(MeshValidation, NoFaces) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}};
  EXPECT_THAT(error_of(m), HasSubstr("the mesh has no faces"));
}

TEST(MeshValidation, NonFiniteCoordinate) {
  TriangleMesh m = two_triangles();
  m.vertices[2].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(error_of(m), HasSubstr("vertex 2 has a non-finite coordinate"));
  m.vertices[2].y = std::numeric_limits<double>::infinity();
  EXPECT_THAT(error_of(m), HasSubstr("vertex 2 has a non-finite coordinate"));
}

TEST(MeshValidation, IndexOutOfRange) {
  TriangleMesh m = two_triangles();
  m.faces[1][2] = 9;
  EXPECT_THAT(error_of(m), HasSubstr("face 1 refers to vertex 9, but the mesh has 4 vertices"));
  m.faces[1][2] = -1;
  EXPECT_THAT(error_of(m), HasSubstr("face 1 refers to vertex -1"));
}

TEST(MeshValidation, FaceUsingAVertexTwice) {
  TriangleMesh m = two_triangles();
  m.faces.push_back({1, 3, 1});
  EXPECT_THAT(error_of(m), HasSubstr("face 2 is degenerate: it uses a vertex twice (1, 3, 1)"));
}

TEST(MeshValidation, ZeroAreaFace) {
  TriangleMesh m = two_triangles();
  m.vertices.push_back({2, 2, 0});  // on the line through vertices 0 and 2
  m.faces.push_back({0, 2, 4});
  EXPECT_THAT(error_of(m), HasSubstr("face 2 is degenerate: its area is zero"));
}

TEST(MeshValidation, DuplicateFaces) {
  TriangleMesh m = two_triangles();
  m.faces.push_back({2, 0, 1});  // face 0 again, rotated
  EXPECT_THAT(error_of(m), HasSubstr("face 0 and face 2 are duplicates"));
}

TEST(MeshValidation, NonManifoldEdge) {
  TriangleMesh m = two_triangles();
  m.vertices.push_back({0.5, 0.5, 1.0});
  m.faces.push_back({0, 2, 4});  // a third face on edge (0, 2)
  EXPECT_THAT(error_of(m),
              HasSubstr("non-manifold edge (0, 2): shared by more than two faces (face 0, face 1, face 2)"));
}

TEST(MeshValidation, InconsistentOrientation) {
  TriangleMesh m = two_triangles();
  m.faces[1] = {2, 0, 3};  // runs 2 → 0 like face 0 (0 → 1 → 2 → 0): one of them is flipped
  EXPECT_THAT(error_of(m), HasSubstr("inconsistent orientation: face 0 and face 1 both run along edge (0, 2)"));
}

TEST(MeshValidation, UnreferencedVertex) {
  TriangleMesh m = two_triangles();
  m.vertices.push_back({5, 5, 5});
  EXPECT_THAT(error_of(m), HasSubstr("vertex 4 is not used by any face"));
}

TEST(MeshValidation, JsonMeshesNameTheJsonPath) {
  TriangleMesh m = two_triangles();
  m.faces[1][2] = 7;
  EXPECT_THAT(error_of(m, {proto::InputLocation::file("mesh.json"), proto::JsonPath{}}),
              HasSubstr("$.triangles[1] refers to vertex 7"));
  m = two_triangles();
  m.vertices.push_back({1, 2, 3});
  EXPECT_THAT(error_of(m, {proto::InputLocation::file("request"), proto::JsonPath{"mesh"}}),
              HasSubstr("$.mesh.vertices[4] is not used by any face"));
}

}  // namespace
}  // namespace texwarp::mesh
