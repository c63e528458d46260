// Flipped UV triangles in the mesh pipeline: an LSCM embedding that flips is replaced by a bijective one, the
// triangles a fold-free warp flips are named (cause "warp") or, with `refine`, split until none flips; features
// inside a face become exact vertices; the refined mesh maps back to the input faces.
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <span>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "mesh_test_shapes.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/mesh/embedding_repair.hpp"
#include "texwarp/mesh/lscm.hpp"
#include "texwarp/mesh/mapping_report.hpp"
#include "texwarp/mesh/mesh_refinement.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/texture_mapping.hpp"

namespace texwarp::mesh {
namespace {

double signed_area(Point a, Point b, Point c) {
  return 0.5 * ((b - a).real() * (c - a).imag() - (b - a).imag() * (c - a).real());
}

// A bent 30×30 grid (a cylinder strip, 1 800 faces) with 12 vertex pins whose sources are the identity mapping's
// texture positions moved by up to ±40 px: seed 47 makes today's UVs flip one face.
struct BentGrid {
  TriangleMesh mesh = testing::cylinder_strip(1.0, 2.0, 2.0, 30, 30);
  MeshRegion region = whole_mesh_region(mesh, proto::InputLocation::file("grid"));
  TextureMappingOptions options;
  SurfaceFeatureSet features;
  CpuBackend backend;
  std::vector<Point> identity_px;  // per region vertex: texture pixels of the mapping without features

  // The warped texture is 512², the texture 600² with the picture 44 px in: pins moved ±40 px stay on the texture
  // (a pin outside it is refused). A common shift of the sources only moves the pre-alignment: the same flips.
  static constexpr double kInset = 44.0;

  explicit BentGrid(std::uint32_t seed = 47, double amplitude = 40.0) {
    options.texture_width = 600;
    options.texture_height = 600;
    options.frame_width = 512;
    options.frame_height = 512;
    // The planner's straight trajectories: lowering their pair energy (the default) leaves this grid no flip.
    features.options.lower_energy = false;
    const TextureMapping identity = map_texture(backend, mesh, region, {}, options);
    identity_px = identity.texture_px;
    for (Point& p : identity_px) p += Point(kInset, kInset);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> pick(0, mesh.vertex_count() - 1);
    std::uniform_real_distribution<double> offset(-amplitude, amplitude);
    for (int k = 0; k < 12; ++k) {
      SurfaceFeature f;
      f.id = "pin" + std::to_string(k);
      const int v = pick(rng);
      f.target = VertexTarget{v};
      const double dx = offset(rng), dy = offset(rng);
      f.source = identity.frame.pixels[region.local_vertex[v]] + Point(kInset + dx, kInset + dy);
      features.features.push_back(f);
    }
  }
};

// Flipped faces counted here, from the mapping's own arrays (independent of uv_metrics).
std::vector<int> flipped_texture_faces(const TextureMapping& m) {
  std::vector<int> out;
  for (int f = 0; f < m.region.face_count(); ++f) {
    const Face& t = m.region.local.faces[f];
    // pixels are y down: a front (counter-clockwise, v up) triangle has a negative pixel-space area
    if (signed_area(m.texture_px[t[0]], m.texture_px[t[1]], m.texture_px[t[2]]) > 0.0) out.push_back(m.region.faces[f]);
  }
  return out;
}

TEST(MeshFlips, TodaysUvsFlipAFaceOfTheBentGridAndTheReportNamesItAsTheWarps) {
  BentGrid g;
  const TextureMapping m = map_texture(g.backend, g.mesh, g.region, g.features, g.options);
  EXPECT_EQ(m.embedding, proto::EmbeddingMethod::kLscm);
  EXPECT_TRUE(m.lscm_flipped_faces.empty());
  const std::vector<int> flipped = flipped_texture_faces(m);
  ASSERT_EQ(flipped.size(), 1u);
  const MappingQuality q = evaluate_mapping(g.mesh, m, m.texture_px, g.options);
  EXPECT_EQ(q.texture.flipped, 1);
  ASSERT_EQ(q.flips.size(), 1u);
  EXPECT_EQ(q.flips[0].face, flipped[0]);
  EXPECT_EQ(q.flips[0].cause, proto::FlipCause::kWarp);
  // The warp itself does not fold there: its Jacobian at the face's centroid (f⁻¹, central differences) is positive.
  const Face& t = g.mesh.faces[flipped[0]];
  Point centre(0, 0);
  for (int v : t) centre += m.frame.pixels[m.region.local_vertex[v]] / 3.0;
  std::vector<Point> probe = {centre + 0.5, centre - 0.5, centre + Point(0, 0.5), centre - Point(0, 0.5)};
  map_points(g.backend, *m.problem, probe, Direction::kInverse);
  const Point dx = probe[0] - probe[1], dy = probe[2] - probe[3];
  EXPECT_GT(dx.real() * dy.imag() - dx.imag() * dy.real(), 0.0);

  const proto::MeshMappingReport r = mesh_mapping_report(g.mesh, m, q, g.options, {});
  ASSERT_EQ(r.flips->size(), 1u);
  EXPECT_EQ((*r.flips)[0].face, flipped[0]);
  EXPECT_FALSE((*r.flips)[0].source_face.has_value());
  EXPECT_EQ(r.uvs.flipped_triangles, 1);
  EXPECT_FALSE(r.refinement.has_value());
}

TEST(MeshFlips, RefineLeavesNoFlippedFaceAndMapsTheOutputBackToTheInputFaces) {
  BentGrid g;
  g.options.refine = true;
  const TextureMapping m = map_texture(g.backend, g.mesh, g.region, g.features, g.options);
  ASSERT_TRUE(m.refinement.has_value());
  const MeshRefinement& x = *m.refinement;
  EXPECT_TRUE(flipped_texture_faces(m).empty());
  EXPECT_GT(x.split_edges, 0);
  const MappingQuality q = evaluate_mapping(g.mesh, m, m.texture_px, g.options, true);
  EXPECT_EQ(q.texture.flipped, 0);
  EXPECT_TRUE(q.flips.empty());
  EXPECT_EQ(q.frame.flipped, 0);

  // Independently: each output face lies in its source face (every corner's 3D position has barycentric weights
  // in [0, 1] in the source face's plane and is on it), output areas per source face sum to the input's area,
  // and the input faces not split are unchanged.
  ASSERT_EQ(static_cast<int>(x.source_face.size()), x.mesh.face_count());
  std::vector<double> area(static_cast<std::size_t>(g.mesh.face_count()), 0.0);
  for (int f = 0; f < x.mesh.face_count(); ++f) {
    const int s = x.source_face[f];
    ASSERT_GE(s, 0);
    ASSERT_LT(s, g.mesh.face_count());
    const Vec3 a = g.mesh.corner(s, 0), b = g.mesh.corner(s, 1), c = g.mesh.corner(s, 2);
    for (int k = 0; k < 3; ++k) {
      const ClosestPoint p = closest_point_on_triangle(x.mesh.corner(f, k), a, b, c);
      EXPECT_LT(p.distance, 1e-12) << "output face " << f << " corner " << k;
    }
    // orientation kept: the output face's normal agrees with the source's
    EXPECT_GT(
        dot(doubled_normal(x.mesh.corner(f, 0), x.mesh.corner(f, 1), x.mesh.corner(f, 2)), doubled_normal(a, b, c)),
        0.0);
    area[s] += triangle_area(x.mesh.corner(f, 0), x.mesh.corner(f, 1), x.mesh.corner(f, 2));
  }
  int split = 0;
  for (int f = 0; f < g.mesh.face_count(); ++f) {
    const Vec3 a = g.mesh.corner(f, 0), b = g.mesh.corner(f, 1), c = g.mesh.corner(f, 2);
    EXPECT_NEAR(area[f], triangle_area(a, b, c), 1e-12) << "input face " << f;
    split += x.mesh.faces[f] != g.mesh.faces[f] ? 1 : 0;
  }
  EXPECT_GT(split, 0);
  // New vertices: their reported input place gives their 3D position.
  ASSERT_EQ(static_cast<int>(x.new_vertices.size()), x.mesh.vertex_count() - g.mesh.vertex_count());
  for (std::size_t i = 0; i < x.new_vertices.size(); ++i) {
    const Vec3 p = surface_position(g.mesh, x.new_vertices[i]);
    EXPECT_LT(norm(p - x.mesh.vertices[g.mesh.vertex_count() + i]), 1e-12) << "new vertex " << i;
  }
  // New vertices' UVs: f⁻¹ of their warped-texture position, as the warp maps it.
  std::vector<Point> expect;
  std::vector<Point> got;
  for (int i = g.mesh.vertex_count(); i < x.mesh.vertex_count(); ++i) {
    expect.push_back(m.frame.pixels[m.region.local_vertex[i]]);
    got.push_back(m.texture_px[m.region.local_vertex[i]]);
  }
  map_points(g.backend, *m.problem, expect, Direction::kInverse);
  // (separate batches of pathlines agree within the integration tolerance)
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_LT(std::abs(got[i] - expect[i]), g.features.options.tolerance_px);

  const proto::MeshMappingReport r = mesh_mapping_report(g.mesh, m, q, g.options, {{}, true, true, 0.0});
  ASSERT_TRUE(r.refinement.has_value());
  EXPECT_EQ(r.refinement->output_faces, x.mesh.face_count());
  EXPECT_EQ(r.refinement->added_vertices, static_cast<int>(x.new_vertices.size()));
  EXPECT_EQ(r.uvs.flipped_triangles, 0);
  ASSERT_TRUE(r.triangles.has_value());
  for (const proto::TriangleReport& t : *r.triangles) {
    ASSERT_TRUE(t.source_face.has_value());
    EXPECT_EQ(*t.source_face, x.source_face[t.face]);
  }
  int flagged = 0;
  for (const proto::VertexReport& v : *r.vertices) {
    EXPECT_EQ(v.source.has_value(), v.vertex >= g.mesh.vertex_count());
    flagged += v.source ? 1 : 0;
  }
  EXPECT_EQ(flagged, static_cast<int>(x.new_vertices.size()));
}

TEST(MeshFlips, RefineMakesAFeatureInsideAFaceExact) {
  BentGrid g;
  // Pins on face interiors and on an edge: today these miss (UVs linear inside the face).
  const std::vector<std::pair<int, Barycentric>> places = {{400, {0.2, 0.3, 0.5}},
                                                           {900, {0.6, 0.1, 0.3}},
                                                           {1201, {0.45, 0.55, 0.0}},
                                                           {1500, {1.0 / 3, 1.0 / 3, 1.0 / 3}}};
  for (std::size_t i = 0; i < places.size(); ++i) {
    SurfaceFeature& f = g.features.features[i];
    const auto& [face, w] = places[i];
    f.target = FaceTarget{face, w};
    f.source = Point(12.0, -8.0);  // moved from where the mapping without features has it
    for (int k = 0; k < 3; ++k) f.source += w[k] * g.identity_px[g.region.local_vertex[g.mesh.faces[face][k]]];
  }
  const TextureMapping plain = map_texture(g.backend, g.mesh, g.region, g.features, g.options);
  const MappingQuality before = evaluate_mapping(g.mesh, plain, plain.texture_px, g.options);
  EXPECT_GT(before.max_residual_px, 1e-2);  // the case exercises the miss refine removes

  g.options.refine = true;
  const TextureMapping m = map_texture(g.backend, g.mesh, g.region, g.features, g.options);
  const MeshRefinement& x = *m.refinement;
  EXPECT_EQ(x.feature_vertices, static_cast<int>(places.size()));
  const MappingQuality q = evaluate_mapping(g.mesh, m, m.texture_px, g.options);
  EXPECT_EQ(q.texture.flipped, 0);
  for (std::size_t i = 0; i < m.features.size(); ++i) {
    // Independent: the feature's point on the input surface is an output vertex; its UV is the source.
    const Vec3 at = surface_position(g.mesh, m.features[i].location);
    int vertex = -1;
    for (int v = 0; v < x.mesh.vertex_count(); ++v) {
      if (norm(x.mesh.vertices[v] - at) < 1e-9) vertex = v;
    }
    ASSERT_GE(vertex, 0) << "feature " << i;
    ASSERT_GE(m.region.local_vertex[vertex], 0);
    EXPECT_LE(std::abs(m.texture_px[m.region.local_vertex[vertex]] - m.features[i].feature.source), 1e-3);
    EXPECT_LE(q.residual_px[i], 1e-3) << "feature " << i;
  }
}

TEST(MeshFlips, AFlippedEmbeddingIsReplacedByABijectiveOne) {
  const TriangleMesh mesh = testing::flat_grid(8, 8, 1.0, 0.2, 3);
  const MeshRegion region = whole_mesh_region(mesh, proto::InputLocation::file("grid"));
  LscmEmbedding lscm = lscm_embedding(region.local, region.boundary);
  ASSERT_TRUE(embedding_flipped_faces(region.local, lscm.positions).empty());
  // Tangle it: an interior vertex pushed across its neighbours.
  std::vector<Point> tangled = lscm.positions;
  const int v = region.local_vertex[4 * 9 + 4];
  tangled[v] += Point(2.6, 0.3);
  const std::vector<int> flipped = embedding_flipped_faces(region.local, tangled);
  ASSERT_FALSE(flipped.empty());
  for (int f : flipped) {  // independently: negative signed area
    const Face& t = region.local.faces[f];
    EXPECT_LE(signed_area(tangled[t[0]], tangled[t[1]], tangled[t[2]]), 0.0);
  }
  const EmbeddingRepair r = repair_embedding(region.local, region.boundary, tangled);
  EXPECT_EQ(r.method, proto::EmbeddingMethod::kMeanValue);
  EXPECT_EQ(r.flipped_faces, flipped);
  double area = 0.0;
  for (const Face& t : region.local.faces) {
    const double a = signed_area(r.positions[t[0]], r.positions[t[1]], r.positions[t[2]]);
    EXPECT_GT(a, 0.0);
    area += a;
  }
  EXPECT_NEAR(area, 64.0, 1e-9);  // scaled to the surface's area
  // The boundary is convex (on a circle): every interior vertex inside it, every boundary vertex on it.
  const EmbeddingRepair kept = repair_embedding(region.local, region.boundary, lscm.positions);
  EXPECT_EQ(kept.method, proto::EmbeddingMethod::kLscm);
  EXPECT_EQ(kept.positions, lscm.positions);
}

TEST(MeshFlips, TheMeanValueEmbeddingOfACurvedCapIsBijective) {
  const TriangleMesh mesh = testing::sphere_cap(1.4, 12, 24);
  const MeshRegion region = whole_mesh_region(mesh, proto::InputLocation::file("cap"));
  const std::vector<Point> p = mean_value_embedding(region.local, region.boundary);
  for (const Face& t : region.local.faces) EXPECT_GT(signed_area(p[t[0]], p[t[1]], p[t[2]]), 0.0);
  // Interior vertices are convex combinations of their neighbours: inside the boundary's circle.
  double radius = 0.0;
  for (int b : region.boundary) radius = std::max(radius, std::abs(p[b]));
  for (int b : region.boundary) EXPECT_NEAR(std::abs(p[b]), radius, 1e-9 * radius);
  for (const Point& q : p) EXPECT_LE(std::abs(q), radius * (1 + 1e-12));
}

// split_feature_edges on a 4×4 grid whose face between three pinned vertices is turned over (two pins' sources
// swapped): every edge joining two pins is split at its midpoint before any pass, counted in split_edges, so that
// afterwards no pin has another as a neighbour.
struct PinEdgeGrid {
  TriangleMesh mesh = testing::flat_grid(4, 4);
  MeshRegion region = whole_mesh_region(mesh, proto::InputLocation::file("grid"));
  // Vertex i + 5 j is column i, row j. Pins 6, 7 and 12 (edges 6–7, 7–12 and, by the grid's diagonals, 6–12 or not:
  // counted from the faces), the sources of 6 and 7 swapped.
  std::vector<int> pins = {6, 7, 12};
  std::vector<PlacedFeature> features;
  std::set<std::pair<int, int>> pin_edges;
  std::vector<Point> frame, embedding, texture;
  RegionVertexData data{frame, embedding, texture};
  RefinementOptions options;

  PinEdgeGrid() {
    for (const int v : region.vertices) {
      const Point p(mesh.vertices[v].x, mesh.vertices[v].y);
      data.frame_px.push_back(100.0 * p);
      data.embedding.push_back(p);
      data.texture_px.push_back(100.0 * p);
    }
    for (const int v : pins) {
      PlacedFeature f;
      for (int face = 0; face < mesh.face_count() && f.location.face < 0; ++face) {
        for (int k = 0; k < 3; ++k) {
          if (mesh.faces[face][k] != v) continue;
          f.location.face = face;
          f.location.barycentric[k] = 1.0;
        }
      }
      f.feature.target = data.frame_px[region.local_vertex[v]];
      f.feature.source = data.texture_px[region.local_vertex[v]];
      features.push_back(f);
    }
    std::swap(features[0].feature.source, features[1].feature.source);
    for (const Face& f : mesh.faces) {
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        if (is_pin(a) && is_pin(b)) pin_edges.emplace(std::min(a, b), std::max(a, b));
      }
    }
    options.texture_width = 500;
    options.texture_height = 500;
    options.bisect = false;
    options.split_feature_edges = true;
  }

  bool is_pin(int v) const { return std::count(pins.begin(), pins.end(), v) > 0; }
  Point source_of(int pin) const {
    return features[std::find(pins.begin(), pins.end(), pin) - pins.begin()].feature.source;
  }
  MeshRefinement refine(const InverseMap& inverse) {
    return refine_region(mesh, region, data, features, inverse, options);
  }

  // No two pins share an edge of `r`'s faces.
  void expect_no_pin_beside_another(const MeshRefinement& r) const {
    for (const Face& f : r.mesh.faces) {
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        EXPECT_FALSE(is_pin(a) && is_pin(b)) << "pins " << a << " and " << b << " are still neighbours";
      }
    }
  }
};

// With `relax` a new vertex's UV is its edge's midpoint UV, which keeps each half's orientation (the flipped face's
// two halves still flip: untangling has the free midpoints to move).
TEST(MeshFlips, SplittingTheEdgesBetweenPinsLeavesNoPinBesideAnother) {
  PinEdgeGrid g;
  ASSERT_GE(g.pin_edges.size(), 2U);
  int relaxed = 0;
  g.options.relax = [&](const TriangleMesh&, std::span<Point>, std::span<const int>) { ++relaxed; };
  const MeshRefinement r = g.refine([](std::span<Point>) { FAIL() << "with relax, new UVs are midpoints"; });
  EXPECT_EQ(r.split_edges, static_cast<int>(g.pin_edges.size()));
  ASSERT_EQ(r.new_vertices.size(), g.pin_edges.size());
  EXPECT_EQ(r.mesh.vertex_count(), g.mesh.vertex_count() + static_cast<int>(g.pin_edges.size()));
  EXPECT_GT(r.flipped_before, 0);
  EXPECT_EQ(relaxed, 1);
  g.expect_no_pin_beside_another(r);
  // Each new vertex sits at its edge's midpoint, in 3D and in UV (the pins' sources as given, 6 and 7 swapped).
  std::size_t n = 0;
  for (const auto& [a, b] : g.pin_edges) {
    const int v = g.mesh.vertex_count() + static_cast<int>(n++);
    const Vec3 mid = 0.5 * (g.mesh.vertices[a] + g.mesh.vertices[b]);
    EXPECT_NEAR(r.mesh.vertices[v].x, mid.x, 1e-12);
    EXPECT_NEAR(r.mesh.vertices[v].y, mid.y, 1e-12);
    const Point uv = g.data.texture_px[g.region.local_vertex[v]];
    EXPECT_NEAR(std::abs(uv - 0.5 * (g.source_of(a) + g.source_of(b))), 0.0, 1e-9) << "edge " << a << "–" << b;
  }
}

// Without `relax` the new vertices' UVs are the warp's inverse at their frame positions (the midpoints there), in
// one call for all of them.
TEST(MeshFlips, SplitPinEdgesTakeTheWarpsInverseWithoutRelax) {
  PinEdgeGrid g;
  const Point shift(3.25, -1.5);
  int calls = 0;
  std::size_t mapped = 0;
  const MeshRefinement r = g.refine([&](std::span<Point> points) {
    ++calls;
    mapped += points.size();
    for (Point& p : points) p = 0.5 * p + shift;  // a map the test knows, unlike any interpolation of the corners
  });
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(mapped, g.pin_edges.size());
  EXPECT_EQ(r.split_edges, static_cast<int>(g.pin_edges.size()));
  g.expect_no_pin_beside_another(r);
  std::size_t n = 0;
  for (const auto& [a, b] : g.pin_edges) {
    const int v = g.mesh.vertex_count() + static_cast<int>(n++);
    const Point frame_mid =
        0.5 * (g.data.frame_px[g.region.local_vertex[a]] + g.data.frame_px[g.region.local_vertex[b]]);
    const Point uv = g.data.texture_px[g.region.local_vertex[v]];
    EXPECT_NEAR(std::abs(uv - (0.5 * frame_mid + shift)), 0.0, 1e-9) << "edge " << a << "–" << b;
  }
}

// The splits count against the vertex bound (a job's memory budget): with room for one vertex, one edge is split
// and the refinement says it stopped at the bound.
TEST(MeshFlips, SplittingPinEdgesStopsAtTheVertexBound) {
  PinEdgeGrid g;
  ASSERT_GE(g.pin_edges.size(), 2U);
  g.options.max_vertices = g.mesh.vertex_count() + 1;
  g.options.relax = [](const TriangleMesh&, std::span<Point>, std::span<const int>) {};
  const MeshRefinement r = g.refine([](std::span<Point>) { FAIL() << "with relax, new UVs are midpoints"; });
  EXPECT_EQ(r.split_edges, 1);
  EXPECT_EQ(r.mesh.vertex_count(), g.mesh.vertex_count() + 1);
  EXPECT_EQ(r.stop, RefinementStop::kVertexLimit);
}

// A region inside a larger mesh whose boundary edges refinement splits (a feature on one, two pins at the ends of
// another with split_feature_edges): the faces outside across those edges take the new vertices too, so that the
// output has no T-junction. Checked on the output alone: every edge is shared by two faces except the grid's own
// outer boundary, which is as it was; the faces tile the same area with none degenerate; each face outside keeps an
// outside face as its source.
TEST(MeshFlips, SplittingARegionsBoundaryEdgeSplitsTheFaceOutsideToo) {
  const TriangleMesh mesh = testing::flat_grid(6, 6);  // vertex i + 7 j at (i, j)
  std::vector<int> inner;
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Vec3 c = (1.0 / 3.0) * (mesh.corner(f, 0) + mesh.corner(f, 1) + mesh.corner(f, 2));
    if (c.x > 2.0 && c.x < 4.0 && c.y > 2.0 && c.y < 4.0) inner.push_back(f);
  }
  MeshRegion region = disk_region(mesh, inner, proto::InputLocation::file("grid"));
  ASSERT_EQ(region.face_count(), 8);
  std::vector<Point> frame, embedding, texture;
  for (const int v : region.vertices) {
    const Point p(mesh.vertices[v].x, mesh.vertices[v].y);
    frame.push_back(50.0 * p);
    embedding.push_back(p);
    texture.push_back(50.0 * p);
  }
  const auto pin = [&](int v) {
    PlacedFeature f;
    for (const int face : region.faces) {
      for (int k = 0; k < 3; ++k) {
        if (mesh.faces[face][k] == v && f.location.face < 0) {
          f.location.face = face;
          f.location.barycentric[k] = 1.0;
        }
      }
    }
    f.feature.target = frame[region.local_vertex[v]];
    f.feature.source = texture[region.local_vertex[v]];
    return f;
  };
  // A feature halfway along the block's bottom edge 16–17, and pins at 25 and 32, the ends of its right edge 25–32.
  PlacedFeature on_edge;
  for (const int face : region.faces) {
    const auto k =
        static_cast<int>(std::find(mesh.faces[face].begin(), mesh.faces[face].end(), 16) - mesh.faces[face].begin());
    const auto l =
        static_cast<int>(std::find(mesh.faces[face].begin(), mesh.faces[face].end(), 17) - mesh.faces[face].begin());
    if (k < 3 && l < 3) {
      on_edge.location.face = face;
      on_edge.location.barycentric[k] = 0.5;
      on_edge.location.barycentric[l] = 0.5;
    }
  }
  ASSERT_GE(on_edge.location.face, 0);
  on_edge.feature.target = on_edge.feature.source =
      0.5 * (frame[region.local_vertex[16]] + frame[region.local_vertex[17]]);
  const std::vector<PlacedFeature> features = {on_edge, pin(25), pin(32)};
  RegionVertexData data{frame, embedding, texture};
  RefinementOptions options;
  options.texture_width = 500;
  options.texture_height = 500;
  options.bisect = false;
  options.split_feature_edges = true;
  options.relax = [](const TriangleMesh&, std::span<Point>, std::span<const int>) {};
  const MeshRefinement r = refine_region(
      mesh, region, data, features, [](std::span<Point>) {}, options);
  EXPECT_EQ(r.feature_vertices, 1);
  EXPECT_EQ(r.split_edges, 1);
  // Two new vertices, each splitting one face inside and one outside.
  EXPECT_EQ(r.mesh.vertex_count(), mesh.vertex_count() + 2);
  EXPECT_EQ(r.mesh.face_count(), mesh.face_count() + 4);
  ASSERT_EQ(r.source_face.size(), static_cast<std::size_t>(r.mesh.face_count()));

  const auto edge_uses = [](const TriangleMesh& m) {
    std::map<std::pair<int, int>, int> uses;
    for (const Face& f : m.faces) {
      for (int k = 0; k < 3; ++k) ++uses[{std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])}];
    }
    return uses;
  };
  std::set<std::pair<int, int>> input_boundary;
  for (const auto& [e, n] : edge_uses(mesh)) {
    if (n == 1) input_boundary.insert(e);
  }
  std::set<std::pair<int, int>> output_boundary;
  for (const auto& [e, n] : edge_uses(r.mesh)) {
    EXPECT_LE(n, 2) << "edge " << e.first << "–" << e.second;
    if (n == 1) output_boundary.insert(e);
  }
  EXPECT_EQ(output_boundary, input_boundary) << "a T-junction leaves edges used once inside the grid";
  // The same area, every face positive in the plane (the grid's orientation) and outside faces' parts from outside.
  double area = 0.0;
  for (int f = 0; f < r.mesh.face_count(); ++f) {
    const Face& t = r.mesh.faces[f];
    const auto at = [&](int v) { return Point(r.mesh.vertices[v].x, r.mesh.vertices[v].y); };
    const double a = signed_area(at(t[0]), at(t[1]), at(t[2]));
    EXPECT_GT(a, 1e-3) << "face " << f;
    area += a;
    const int source = r.source_face[f];
    const bool inside = std::find(inner.begin(), inner.end(), source) != inner.end();
    EXPECT_EQ(inside, region.local_face[f] >= 0) << "face " << f << " from input face " << source;
  }
  EXPECT_NEAR(area, 36.0, 1e-9);
}

}  // namespace
}  // namespace texwarp::mesh
