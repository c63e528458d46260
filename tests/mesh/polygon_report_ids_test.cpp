// The mesh report of a quad OBJ and an n-gon OBJ, with and without refine, through the pipeline map-mesh and mesh
// jobs run: every face id it reports on the input mesh is the file's `f` line, computed here from the OBJ's own
// layout (which cell of the sheet a point lies in), never from texwarp's triangle-to-face table.
#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/mesh/input_faces.hpp"
#include "texwarp/mesh/mapping_report.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/texture_mapping.hpp"

namespace texwarp::mesh {
namespace {

double height_at(double x) { return 0.1 * (x - 0.5) * (x - 0.5); }

// A unit sheet of `columns` × `rows` faces written as an OBJ, face (c, r) on f line r·columns + c. Each face spans
// `cells` grid cells across: 1 gives quads, 2 hexagons (the mid-edge vertices shared with the faces above and below).
struct PolygonSheet {
  int columns = 0;
  int rows = 0;
  int cells = 1;
  std::string obj;

  PolygonSheet(int face_columns, int face_rows, int face_cells)
      : columns(face_columns), rows(face_rows), cells(face_cells) {
    const int nx = columns * cells + 1;
    for (int j = 0; j <= rows; ++j) {
      for (int i = 0; i < nx; ++i) {
        const double x = static_cast<double>(i) / (nx - 1);
        obj += "v " + std::to_string(x) + " " + std::to_string(static_cast<double>(j) / rows) + " " +
               std::to_string(height_at(x)) + "\n";
      }
    }
    const auto id = [&](int i, int j) { return std::to_string(j * nx + i + 1); };
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < columns; ++c) {
        std::string f = "f";
        for (int k = 0; k <= cells; ++k) f += " " + id(c * cells + k, r);      // bottom, left to right
        for (int k = cells; k >= 0; --k) f += " " + id(c * cells + k, r + 1);  // top, right to left
        obj += f + "\n";
      }
    }
  }

  // The f lines whose closed cell holds (x, y) (more than one on a shared edge).
  std::set<int> faces_at(double x, double y) const {
    constexpr double kEps = 1e-6;  // the OBJ holds 6 decimals
    std::set<int> out;
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < columns; ++c) {
        const double x0 = static_cast<double>(c) / columns, x1 = static_cast<double>(c + 1) / columns;
        const double y0 = static_cast<double>(r) / rows, y1 = static_cast<double>(r + 1) / rows;
        if (x >= x0 - kEps && x <= x1 + kEps && y >= y0 - kEps && y <= y1 + kEps) out.insert(r * columns + c);
      }
    }
    return out;
  }
  int face_at(double x, double y) const {
    const std::set<int> f = faces_at(x, y);
    EXPECT_EQ(f.size(), 1u) << "(" << x << ", " << y << ") is on an edge";
    return f.empty() ? -1 : *f.begin();
  }
};

// The OBJ text's `v` lines (positions) and `f` lines (0-based vertex ids), read here, not by texwarp's reader.
std::vector<std::array<double, 3>> obj_vertices(const std::string& obj) {
  std::vector<std::array<double, 3>> out;
  std::istringstream lines(obj);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream in(line);
    std::string tag;
    std::array<double, 3> p{};
    if (in >> tag && tag == "v" && in >> p[0] >> p[1] >> p[2]) out.push_back(p);
  }
  return out;
}

std::vector<std::vector<int>> obj_faces(const std::string& obj) {
  std::vector<std::vector<int>> out;
  std::istringstream lines(obj);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream in(line);
    std::string tag;
    if (!(in >> tag) || tag != "f") continue;
    out.emplace_back();
    for (int id = 0; in >> id;) out.back().push_back(id - 1);
  }
  return out;
}

double signed_area(Point a, Point b, Point c) {
  return 0.5 * ((b - a).real() * (c - a).imag() - (b - a).imag() * (c - a).real());
}

struct Mapped {
  MeshFile file;
  TextureMapping mapping;
  MappingQuality quality;
  proto::MeshMappingReport report;
};

// Point features inside chosen faces (away from their edges), sources a mirrored layout of the sheet (the warp
// then flips UV triangles to name).
const std::vector<std::array<double, 2>> kFeaturePoints = {{0.08, 0.11}, {0.61, 0.14}, {0.37, 0.45},
                                                           {0.88, 0.55}, {0.22, 0.79}, {0.71, 0.93}};

Mapped map_sheet(const PolygonSheet& sheet, bool refine) {
  Mapped m{parse_obj_file(sheet.obj, proto::InputLocation::file("sheet.obj")), {}, {}, {}};
  SurfaceFeatureSet features;
  for (std::size_t k = 0; k < kFeaturePoints.size(); ++k) {
    const auto [x, y] = kFeaturePoints[k];
    SurfaceFeature f;
    f.id = "p" + std::to_string(k);
    f.target = PointTarget{{x, y, height_at(x)}};
    const double dx = k % 2 == 0 ? 14.0 : -11.0, dy = k % 3 == 0 ? -9.0 : 12.0;
    f.source = Point(56.0 + 400.0 * x + dx, 56.0 + 400.0 * y + dy);  // v down the sheet: mirrored
    features.features.push_back(f);
  }
  TextureMappingOptions options;
  options.texture_width = 512;
  options.texture_height = 512;
  options.refine = refine;
  CpuBackend backend;
  const MeshRegion region = whole_mesh_region(m.file.mesh, proto::InputLocation::file("sheet.obj"));
  m.mapping = map_texture(backend, m.file.mesh, region, features_on_triangles(features, m.file.faces), options);
  m.quality = evaluate_mapping(m.file.mesh, m.mapping, m.mapping.texture_px, options, true);
  m.report = mesh_mapping_report(m.file.mesh, m.mapping, m.quality, options, {{}, true, true, 0.0});
  name_input_faces(m.report, m.file.faces, m.mapping.region.faces);
  return m;
}

Vec3 centroid(const TriangleMesh& mesh, int face) {
  return (mesh.corner(face, 0) + mesh.corner(face, 1) + mesh.corner(face, 2)) / 3.0;
}

void expect_file_faces(const PolygonSheet& sheet, bool refine) {
  SCOPED_TRACE(std::string(sheet.cells == 1 ? "quads" : "hexagons") + (refine ? ", refine" : ""));
  const Mapped m = map_sheet(sheet, refine);
  const proto::MeshMappingReport& r = m.report;
  const TriangleMesh& out_mesh = output_mesh(m.file.mesh, m.mapping.refinement);
  EXPECT_EQ(r.mesh.faces, sheet.columns * sheet.rows);
  ASSERT_EQ(r.refinement.has_value(), refine);

  // Each feature names the f line holding its point.
  ASSERT_EQ(r.features.size(), kFeaturePoints.size());
  for (std::size_t k = 0; k < r.features.size(); ++k) {
    EXPECT_EQ(r.features[k].face, sheet.face_at(kFeaturePoints[k][0], kFeaturePoints[k][1])) << "feature " << k;
  }

  // Per triangle and flips: without refine the f line holding the triangle; with refine the output triangle
  // (mesh.obj written anew) and its source_face the f line holding it.
  ASSERT_TRUE(r.triangles.has_value());
  ASSERT_EQ(static_cast<int>(r.triangles->size()), m.mapping.region.face_count());
  std::set<int> expected_flips;
  for (int i = 0; i < m.mapping.region.face_count(); ++i) {
    const int triangle = m.mapping.region.faces[i];
    const Vec3 c = centroid(out_mesh, triangle);
    const int file_face = sheet.face_at(c.x, c.y);
    const proto::TriangleReport& t = (*r.triangles)[i];
    if (refine) {
      EXPECT_EQ(t.face, triangle);
      ASSERT_TRUE(t.source_face.has_value());
      EXPECT_EQ(*t.source_face, file_face) << "output triangle " << triangle;
    } else {
      EXPECT_EQ(t.face, file_face) << "triangle " << triangle;
      EXPECT_FALSE(t.source_face.has_value());
    }
    const Face& l = m.mapping.region.local.faces[i];
    const std::vector<Point>& px = m.mapping.texture_px;
    if (signed_area(px[l[0]], px[l[1]], px[l[2]]) > 0.0) expected_flips.insert(refine ? triangle : file_face);
  }
  std::set<int> reported_flips;
  for (const proto::FlippedFaceReport& f : r.flips.value()) {
    reported_flips.insert(f.face);
    EXPECT_EQ(f.source_face.has_value(), refine);
  }
  EXPECT_EQ(reported_flips, expected_flips);
  if (!refine) {
    EXPECT_FALSE(expected_flips.empty()) << "the case wants flipped triangles to name";
  }

  // A vertex refine added lies in the f line its source names (either one on a shared edge); its weights over its
  // corners, vertices of that f line, give back its position (the corners' positions read from the OBJ's text).
  const std::vector<std::array<double, 3>> file_vertices = obj_vertices(sheet.obj);
  const std::vector<std::vector<int>> file_faces = obj_faces(sheet.obj);
  ASSERT_TRUE(r.vertices.has_value());
  int added = 0;
  for (const proto::VertexReport& v : *r.vertices) {
    if (!v.source) continue;
    ++added;
    const Vec3 p = out_mesh.vertices[v.vertex];
    EXPECT_TRUE(sheet.faces_at(p.x, p.y).contains(v.source->face))
        << "vertex " << v.vertex << " at (" << p.x << ", " << p.y << ") named face " << v.source->face;
    ASSERT_TRUE(v.source->corners.has_value()) << "vertex " << v.vertex;
    const std::vector<int>& f_line = file_faces.at(static_cast<std::size_t>(v.source->face));
    std::array<double, 3> q{};
    for (int k = 0; k < 3; ++k) {
      const int c = (*v.source->corners)[k];
      EXPECT_NE(std::find(f_line.begin(), f_line.end(), c), f_line.end())
          << "vertex " << v.vertex << ": corner " << c << " is not on f line " << v.source->face;
      for (int d = 0; d < 3; ++d) q[d] += v.source->barycentric[k] * file_vertices.at(static_cast<std::size_t>(c))[d];
    }
    EXPECT_NEAR(q[0], p.x, 1e-9) << "vertex " << v.vertex;
    EXPECT_NEAR(q[1], p.y, 1e-9) << "vertex " << v.vertex;
    EXPECT_NEAR(q[2], p.z, 1e-9) << "vertex " << v.vertex;
  }
  EXPECT_EQ(added > 0, refine);

  // The faces LSCM flipped (none on this sheet: set here as the pipeline records them, triangles of the input
  // mesh, two f lines' triangles in scrambled order) are reported as those f lines, each once.
  const std::set<int> chosen = {sheet.face_at(0.55, 0.3), sheet.face_at(0.1, 0.9)};
  TextureMapping tangled = m.mapping;
  tangled.lscm_flipped_faces.clear();
  for (int t = m.file.mesh.face_count() - 1; t >= 0; --t) {
    const Vec3 c = centroid(m.file.mesh, t);
    if (chosen.contains(sheet.face_at(c.x, c.y))) tangled.lscm_flipped_faces.push_back(t);
  }
  ASSERT_GT(tangled.lscm_flipped_faces.size(), chosen.size());
  TextureMappingOptions options;
  options.texture_width = options.texture_height = 512;
  proto::MeshMappingReport named = mesh_mapping_report(m.file.mesh, tangled, m.quality, options, {});
  name_input_faces(named, m.file.faces, tangled.region.faces);
  EXPECT_EQ(named.embedding->lscm_flipped_faces, std::vector<int>(chosen.begin(), chosen.end()));
}

TEST(PolygonReportIds, QuadObjReportsTheFilesFaces) { expect_file_faces(PolygonSheet(6, 6, 1), false); }
TEST(PolygonReportIds, QuadObjReportsTheFilesFacesWithRefine) { expect_file_faces(PolygonSheet(6, 6, 1), true); }
TEST(PolygonReportIds, HexagonObjReportsTheFilesFaces) { expect_file_faces(PolygonSheet(3, 6, 2), false); }
TEST(PolygonReportIds, HexagonObjReportsTheFilesFacesWithRefine) { expect_file_faces(PolygonSheet(3, 6, 2), true); }

}  // namespace
}  // namespace texwarp::mesh
