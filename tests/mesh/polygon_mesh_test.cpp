// Quads and n-gons: ear clipping of convex and non-convex polygons (checked against the shoelace area), OBJ faces
// mapped to their triangles and back (regions, face targets, reports), and the textured OBJ that keeps every input
// line it does not change, read back with tinyobjloader.
#include <array>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tiny_obj_loader.h>

#include "input_error_text.hpp"
#include "texwarp/mesh/input_faces.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/mesh/obj_output.hpp"
#include "texwarp/mesh/polygon_triangulation.hpp"
#include "texwarp/mesh/region_spec.hpp"

namespace texwarp::mesh {
namespace {

using ::testing::HasSubstr;
using texwarp::testing::input_error_of;

const proto::InputLocation kFile = proto::InputLocation::file("shapes.obj");

// Twice the signed area of a triangle in the xy plane.
double area2(const std::vector<Vec3>& p, const Face& f) {
  const Vec3 a = p[f[0]], b = p[f[1]], c = p[f[2]];
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// Twice the signed area of a polygon in the xy plane (shoelace).
double shoelace2(const std::vector<Vec3>& p, const std::vector<int>& poly) {
  double s = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec3 a = p[poly[i]], b = p[poly[(i + 1) % poly.size()]];
    s += a.x * b.y - b.x * a.y;
  }
  return s;
}

TEST(PolygonTriangulation, ConvexAndNonConvexPolygonsAreCoveredExactlyOnce) {
  // An L-shaped hexagon (reflex corner at vertex 3), a convex pentagon, and a comb with two reflex corners, each
  // lifted onto a tilted plane so that the triangulation works in the polygon's own plane.
  const std::vector<std::vector<std::array<double, 2>>> shapes = {
      {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}},
      {{0, 0}, {2, 0}, {3, 1}, {1, 3}, {-1, 1}},
      {{0, 0}, {5, 0}, {5, 3}, {4, 3}, {4, 1}, {3, 1}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}}};
  for (const auto& shape : shapes) {
    std::vector<Vec3> flat, tilted;
    std::vector<int> poly;
    for (const auto& q : shape) {
      poly.push_back(static_cast<int>(flat.size()));
      flat.push_back({q[0], q[1], 0});
      tilted.push_back({q[0], q[1] * 0.6, q[1] * 0.8});  // rotated about x: same shape in its plane
    }
    const std::vector<Face> triangles = triangulate_polygon(poly, tilted);
    ASSERT_EQ(triangles.size(), poly.size() - 2);
    double sum = 0;
    for (const Face& t : triangles) {
      EXPECT_GT(area2(flat, t), 0.0);  // every triangle keeps the polygon's (counter-clockwise) orientation
      sum += area2(flat, t);
    }
    EXPECT_NEAR(sum, shoelace2(flat, poly), 1e-12);  // positive pieces summing to the area: no overlap, no gap
  }
}

TEST(PolygonTriangulation, LargeConvexPolygonsAreFannedLargeNonConvexOnesRefused) {
  // A convex 100-gon (a circle) and a 40-vertex star (every other vertex pulled in: non-convex).
  std::vector<Vec3> circle, star;
  std::vector<int> ids100, ids40;
  for (int i = 0; i < 100; ++i) {
    circle.push_back({std::cos(i * 2 * M_PI / 100), std::sin(i * 2 * M_PI / 100), 0});
    ids100.push_back(i);
  }
  for (int i = 0; i < 40; ++i) {
    const double r = i % 2 == 0 ? 1.0 : 0.5;
    star.push_back({r * std::cos(i * 2 * M_PI / 40), r * std::sin(i * 2 * M_PI / 40), 0});
    ids40.push_back(i);
  }
  const std::vector<Face> fan = triangulate_polygon(ids100, circle);
  ASSERT_EQ(fan.size(), 98u);
  double sum = 0;
  for (const Face& t : fan) sum += area2(circle, t);
  EXPECT_NEAR(sum, shoelace2(circle, ids100), 1e-12);
  EXPECT_TRUE(triangulate_polygon(ids40, star).empty());
  const std::vector<int> ids20(ids40.begin(), ids40.begin() + 20);  // half the star plus its centre: 21 vertices
  std::vector<Vec3> half = star;
  half.push_back({0, 0, 0});
  std::vector<int> ids21 = ids20;
  ids21.push_back(40);
  EXPECT_EQ(triangulate_polygon(ids21, half).size(), 19u);
}

TEST(PolygonTriangulation, SelfIntersectingAndDegeneratePolygonsHaveNone) {
  const std::vector<Vec3> bow_tie = {{0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0}};
  EXPECT_TRUE(triangulate_polygon(std::vector<int>{0, 1, 2, 3}, bow_tie).empty());
  const std::vector<Vec3> line = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  EXPECT_TRUE(triangulate_polygon(std::vector<int>{0, 1, 2, 3}, line).empty());
}

// A 3×1 strip: a quad, a pentagon (an extra vertex on its top edge) and two triangles, with what an exporter
// writes around them: comments, mtllib/usemtl, objects, groups, smoothing, normals, UVs of every face.
const std::string kObj = "# exported by a DCC tool\r\n"
                         "mtllib shapes.mtl\n"
                         "o strip\n"
                         "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\n"
                         "v 0 1 0\nv 1 1 0\nv 2 1 0\nv 3 1 0\nv 1.5 1 0\n"
                         "vt 0 0\nvt 0.25 0\nvt 0.5 0\nvt 0.75 0\n"
                         "vn 0 0 1\n"
                         "g left\n"
                         "usemtl red\n"
                         "s 1\n"
                         "f 1/1/1 2/2/1 6/2/1 5/1/1\n"
                         "g middle\n"
                         "usemtl blue\n"
                         "s off\n"
                         "f 2/2/1 3/3/1 7/3/1 9/4/1 6/2/1\n"
                         "# the right square as two triangles\n"
                         "g right\n"
                         "f 3//1 4//1 8//1\n"
                         "f -7 -2 -3\n";

TEST(ObjPolygons, FacesAreTriangulatedAndMappedBack) {
  const MeshFile file = parse_obj_file(kObj, kFile);
  EXPECT_NO_THROW(validate_mesh(file.mesh, MeshSource{kFile, std::nullopt}));
  EXPECT_EQ(file.faces.count(), 4);
  EXPECT_EQ(file.mesh.face_count(), 2 + 3 + 1 + 1);
  EXPECT_EQ(file.faces.first_triangle, (std::vector<int>{0, 2, 5, 6, 7}));
  EXPECT_EQ(file.faces.of_triangle, (std::vector<int>{0, 0, 1, 1, 1, 2, 3}));
  EXPECT_EQ(file.mesh.faces[6], (Face{2, 7, 6}));  // "f -7 -2 -3": relative to the 9 vertices before it

  // A region of input faces 0 and 1 is their five triangles; a seed face is its first triangle.
  proto::RegionSpec spec;
  spec.faces = {1, 0};
  EXPECT_EQ(region_on_triangles(spec, file.faces, kFile).faces, (std::vector<int>{2, 3, 4, 0, 1}));
  spec.faces = {4};
  EXPECT_THAT(input_error_of([&] { region_on_triangles(spec, file.faces, kFile); }),
              HasSubstr("shapes.obj: $.faces[0]: face 4 does not exist (the mesh has 4 faces)"));

  // A face target on a triangle moves to its triangle; on a polygon it is refused.
  SurfaceFeatureSet set;
  set.features.push_back({"a", {1, 1}, FaceTarget{3, {0.2, 0.3, 0.5}}, std::nullopt, std::nullopt});
  EXPECT_EQ(std::get<FaceTarget>(features_on_triangles(set, file.faces).features[0].target).face, 6);
  set.features.push_back({"b", {2, 2}, FaceTarget{1, {0.2, 0.3, 0.5}}, std::nullopt, std::nullopt});
  EXPECT_THAT(input_error_of([&] { features_on_triangles(set, file.faces); }),
              HasSubstr("$.features[1].target.face: face 1 is a polygon"));

  // Reports name input faces.
  proto::MeshMappingReport report;
  report.triangles = std::vector<proto::TriangleReport>(7);
  for (int t = 0; t < 7; ++t) (*report.triangles)[t].face = t;
  name_input_faces(report, file.faces, std::vector<int>{2, 3, 4, 0, 1});
  std::vector<int> named;
  for (const auto& t : *report.triangles) named.push_back(t.face);
  EXPECT_EQ(named, file.faces.of_triangle);
}

TEST(ObjPolygons, PolygonsThatCannotBeTriangulatedAreRefused) {
  EXPECT_THAT(input_error_of([] { parse_obj_file("v 0 0 0\nv 1 1 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 4\n", kFile); }),
              HasSubstr("shapes.obj: face 0 (4 vertices) cannot be triangulated"));
  EXPECT_THAT(input_error_of([] { parse_obj_file("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 9\n", kFile); }),
              HasSubstr("face 0 uses vertex 9, which does not exist"));
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(ObjOutput, EveryLineOutsideTheRegionsFacesIsKeptByteForByte) {
  const MeshFile file = parse_obj_file(kObj, kFile);
  proto::RegionSpec spec;
  spec.faces = {1, 3};  // the pentagon and the last triangle, which share the edge 3–7
  const MeshRegion region = select_region(file.mesh, region_on_triangles(spec, file.faces, kFile), kFile);
  std::vector<std::array<double, 2>> uvs;
  for (const int v : region.vertices) uvs.push_back({0.5 + 0.125 * v, 0.0625 * v});
  const std::string out = textured_obj_text(kObj, file.mesh, file.faces, region, uvs, "texwarp test");

  const std::vector<std::string> in_lines = lines_of(kObj);
  const std::vector<std::string> out_lines = lines_of(out);
  ASSERT_EQ(out_lines.size(), 1 + in_lines.size() + uvs.size());
  EXPECT_EQ(out_lines[0], "# texwarp test");
  // Region vertices (0-based) 1, 2, 5, 6, 7, 8 are local 0…5; after the input's 4 vt, local k is vt 5 + k.
  for (std::size_t i = 0; i < in_lines.size(); ++i) {
    const std::string& line = in_lines[i];
    if (line == "f 2/2/1 3/3/1 7/3/1 9/4/1 6/2/1") {
      EXPECT_EQ(out_lines[1 + i], "f 2/5/1 3/6/1 7/8/1 9/10/1 6/7/1");
    } else if (line == "f -7 -2 -3") {
      EXPECT_EQ(out_lines[1 + i], "f -7/6 -2/9 -3/8");
    } else {
      EXPECT_EQ(out_lines[1 + i], line);  // kept: comments (with their \r), mtllib, groups, normals, other faces
    }
  }
  EXPECT_EQ(out_lines.back(), "vt 1.5 0.5");  // local 5 is mesh vertex 8

  // Read back by tinyobjloader: region corners carry their vertex's new UV, the others their old one.
  tinyobj::ObjReader reader;
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;
  ASSERT_TRUE(reader.ParseFromString(out, "", config)) << reader.Error();
  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  ASSERT_EQ(attrib.texcoords.size(), 2 * (4 + uvs.size()));
  int face = 0;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    std::size_t offset = 0;
    for (const unsigned char count : shape.mesh.num_face_vertices) {
      for (std::size_t k = 0; k < count; ++k) {
        const tinyobj::index_t& c = shape.mesh.indices[offset + k];
        if (face == 1 || face == 3) {
          const auto& uv = uvs[region.local_vertex[c.vertex_index]];
          const std::size_t at = std::size_t{2} * static_cast<std::size_t>(c.texcoord_index);
          EXPECT_DOUBLE_EQ(attrib.texcoords[at], uv[0]);
          EXPECT_DOUBLE_EQ(attrib.texcoords[at + 1], uv[1]);
          EXPECT_EQ(c.normal_index, face == 1 ? 0 : -1);
        } else if (face == 0) {
          EXPECT_LT(c.texcoord_index, 4);
        } else {
          EXPECT_EQ(c.texcoord_index, -1);  // "f 3//1 4//1 8//1" had none and keeps none
        }
      }
      offset += count;
      ++face;
    }
  }
  EXPECT_EQ(face, 4);
  // texwarp reads it back to the same mesh.
  EXPECT_EQ(parse_obj_file(out, kFile).mesh.faces, file.mesh.faces);
}

}  // namespace
}  // namespace texwarp::mesh
