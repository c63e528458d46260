// Untangling (core/mesh/uv_untangling.hpp): a fold of free vertices is unfolded with the held vertices bit for bit
// where they were, and in a large region the vertices far from it too; a triangle whose corners are all held stays as
// it is and nothing is made worse; a flip-free map is left alone; cancellation leaves the UVs unchanged. Orientation is
// checked here from signed areas, independently of the library's checks.
#include <algorithm>
#include <atomic>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>

#include "mesh_test_shapes.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/mesh/uv_untangling.hpp"

namespace texwarp::mesh {
namespace {

constexpr int kGrid = 10;  // flat_grid(10, 10): vertex (i, j) at j·11 + i

int vertex(int i, int j) { return j * (kGrid + 1) + i; }

double signed_area(Point a, Point b, Point c) {
  return 0.5 * ((b.real() - a.real()) * (c.imag() - a.imag()) - (b.imag() - a.imag()) * (c.real() - a.real()));
}

int negative_faces(const TriangleMesh& mesh, const std::vector<Point>& uv) {
  return static_cast<int>(std::count_if(mesh.faces.begin(), mesh.faces.end(), [&](const Face& f) {
    return !(signed_area(uv[f[0]], uv[f[1]], uv[f[2]]) > 0.0);
  }));
}

const UvTriangleCheck kPositive = [](Point a, Point b, Point c) { return signed_area(a, b, c) > 0.0; };

// The grid's own positions, 8 units per step: a flip-free map.
std::vector<Point> identity_uvs(const TriangleMesh& mesh) {
  std::vector<Point> uv;
  for (const Vec3& v : mesh.vertices) uv.emplace_back(8.0 * v.x, 8.0 * v.y);
  return uv;
}

// The boundary and two interior vertices held.
std::vector<int> held_vertices() {
  std::vector<int> held;
  for (int i = 0; i <= kGrid; ++i) {
    for (int j = 0; j <= kGrid; ++j) {
      if (i == 0 || j == 0 || i == kGrid || j == kGrid) held.push_back(vertex(i, j));
    }
  }
  held.push_back(vertex(2, 7));
  held.push_back(vertex(8, 3));
  return held;
}

TEST(UvUntangling, UnfoldsAFoldOfFreeVerticesWithTheHeldOnesWhereTheyWere) {
  const TriangleMesh mesh = testing::flat_grid(kGrid, kGrid);
  std::vector<Point> uv = identity_uvs(mesh);
  // A 4×4 patch of free vertices mirrored left to right about its middle: every face among them turns over.
  for (int j = 3; j <= 6; ++j) {
    for (int i = 3; i <= 6; ++i) uv[vertex(i, j)] = Point(8.0 * (9 - i), 8.0 * j);
  }
  const std::vector<Point> start = uv;
  const int before = negative_faces(mesh, uv);
  ASSERT_GE(before, 18);  // the patch's 9 quads at least
  const std::vector<int> held = held_vertices();
  const UvUntangling u = untangle_uvs(mesh, uv, held, kPositive);
  EXPECT_EQ(u.rejected_before, before);
  EXPECT_TRUE(u.applied);
  EXPECT_EQ(u.rejected_after, 0);
  EXPECT_GT(u.rounds, 0);
  EXPECT_EQ(negative_faces(mesh, uv), 0);
  for (int v : held) EXPECT_EQ(uv[v], start[v]) << "held vertex " << v;
  // The free vertices stay inside the held boundary's square (a fold undone, not pushed out).
  for (const Point p : uv) {
    EXPECT_GE(p.real(), 0.0);
    EXPECT_LE(p.real(), 8.0 * kGrid);
    EXPECT_GE(p.imag(), 0.0);
    EXPECT_LE(p.imag(), 8.0 * kGrid);
  }
}

// Edges from the corners of the faces that `uv` turns over to each vertex (breadth first over the faces' edges).
std::vector<int> rings_from_flips(const TriangleMesh& mesh, const std::vector<Point>& uv) {
  std::vector<int> ring(mesh.vertices.size(), -1);
  std::vector<int> frontier;
  for (const Face& f : mesh.faces) {
    if (signed_area(uv[f[0]], uv[f[1]], uv[f[2]]) > 0.0) continue;
    for (const int v : f) {
      if (ring[v] < 0) {
        ring[v] = 0;
        frontier.push_back(v);
      }
    }
  }
  for (int r = 1; !frontier.empty(); ++r) {
    std::vector<int> next;
    for (const Face& f : mesh.faces) {
      for (const int v : f) {
        if (ring[v] != r - 1) continue;
        for (const int w : f) {
          if (ring[w] < 0) {
            ring[w] = r;
            next.push_back(w);
          }
        }
      }
    }
    frontier = std::move(next);
  }
  return ring;
}

// A fold in a large region: only the vertices near it move (the cost of a round follows the fold, not the region),
// and the rest stay bit for bit where they were; with every vertex free from the start (rings −1) the far ones move
// too, so the first check can fail.
TEST(UvUntangling, AFoldInALargeRegionMovesOnlyTheVerticesAroundIt) {
  constexpr int kLarge = 48;
  const TriangleMesh mesh = testing::flat_grid(kLarge, kLarge);
  const auto at = [](int i, int j) { return j * (kLarge + 1) + i; };
  std::vector<Point> uv = identity_uvs(mesh);
  for (int j = 20; j <= 23; ++j) {
    for (int i = 20; i <= 23; ++i) uv[at(i, j)] = Point(8.0 * (43 - i), 8.0 * j);
  }
  std::vector<int> held;
  for (int i = 0; i <= kLarge; ++i) {
    for (int j = 0; j <= kLarge; ++j) {
      if (i == 0 || j == 0 || i == kLarge || j == kLarge) held.push_back(at(i, j));
    }
  }
  const std::vector<Point> start = uv;
  const std::vector<int> ring = rings_from_flips(mesh, uv);
  ASSERT_GT(negative_faces(mesh, uv), 0);

  UvUntanglingOptions local;
  ASSERT_EQ(local.rings, 8);
  const UvUntangling u = untangle_uvs(mesh, uv, held, kPositive, local);
  EXPECT_EQ(u.rejected_after, 0);
  EXPECT_EQ(negative_faces(mesh, uv), 0);
  int far = 0;
  for (std::size_t v = 0; v < uv.size(); ++v) {
    if (ring[v] <= local.rings) continue;
    ++far;
    EXPECT_EQ(uv[v], start[v]) << "vertex " << v << ", " << ring[v] << " edges from the fold";
  }
  EXPECT_GT(far, 1500);

  std::vector<Point> whole_uv = start;
  UvUntanglingOptions whole;
  whole.rings = -1;
  EXPECT_EQ(untangle_uvs(mesh, whole_uv, held, kPositive, whole).rejected_after, 0);
  int moved_far = 0;
  for (std::size_t v = 0; v < uv.size(); ++v) moved_far += ring[v] > local.rings && whole_uv[v] != start[v];
  EXPECT_GT(moved_far, 0);
}

// Two grids side by side, apart: in the first every vertex is held and two are swapped (turned-over triangles that
// nothing can unfold), the second has free vertices and no flip. No ring around the flips reaches a free vertex;
// the untangling ends, changing nothing.
TEST(UvUntangling, ARegionInTwoPiecesEndsWhenNoRingReachesAFreeVertex) {
  const TriangleMesh piece = testing::flat_grid(kGrid, kGrid);
  TriangleMesh mesh = piece;
  const int offset = static_cast<int>(piece.vertices.size());
  for (const Vec3& v : piece.vertices) mesh.vertices.push_back(Vec3{v.x + 2.0 * kGrid, v.y, v.z});
  for (const Face& f : piece.faces) mesh.faces.push_back(Face{f[0] + offset, f[1] + offset, f[2] + offset});
  std::vector<Point> uv = identity_uvs(mesh);
  std::swap(uv[vertex(4, 4)], uv[vertex(5, 4)]);
  std::vector<int> held(static_cast<std::size_t>(offset));
  std::iota(held.begin(), held.end(), 0);
  for (const int v : held_vertices()) held.push_back(v + offset);
  const std::vector<Point> start = uv;
  const int before = negative_faces(mesh, uv);
  ASSERT_GT(before, 0);
  UvUntanglingOptions options;
  options.rings = 1;
  const UvUntangling u = untangle_uvs(mesh, uv, held, kPositive, options);
  EXPECT_EQ(u.rejected_after, before);
  EXPECT_FALSE(u.applied);
  EXPECT_EQ(uv, start);
}

TEST(UvUntangling, LeavesATriangleWhoseCornersAreAllHeldAndMakesNothingWorse) {
  const TriangleMesh mesh = testing::flat_grid(kGrid, kGrid);
  std::vector<Point> uv = identity_uvs(mesh);
  // Two neighbouring interior vertices held with their places swapped: the faces holding both with a third held
  // corner cannot turn, the others can.
  std::vector<int> held = held_vertices();
  const int a = vertex(4, 4), b = vertex(5, 4), c = vertex(5, 5);
  held.insert(held.end(), {a, b, c});
  std::swap(uv[a], uv[b]);
  const std::vector<Point> start = uv;
  const int before = negative_faces(mesh, uv);
  ASSERT_GT(before, 0);
  // The faces whose three corners are held and which are turned over: no map of these faces unfolds them.
  int stuck = 0;
  for (const Face& f : mesh.faces) {
    const bool all_held =
        std::all_of(f.begin(), f.end(), [&](int v) { return std::find(held.begin(), held.end(), v) != held.end(); });
    if (all_held && !(signed_area(uv[f[0]], uv[f[1]], uv[f[2]]) > 0.0)) ++stuck;
  }
  ASSERT_GT(stuck, 0);
  const UvUntangling u = untangle_uvs(mesh, uv, held, kPositive);
  EXPECT_EQ(u.rejected_before, before);
  EXPECT_GE(u.rejected_after, stuck);
  EXPECT_LE(u.rejected_after, before);
  EXPECT_EQ(negative_faces(mesh, uv), u.rejected_after);
  for (int v : held) EXPECT_EQ(uv[v], start[v]) << "held vertex " << v;
  if (!u.applied) {
    EXPECT_EQ(uv, start);
  }
}

TEST(UvUntangling, LeavesAFlipFreeMapAlone) {
  const TriangleMesh mesh = testing::flat_grid(kGrid, kGrid, 1.0, 0.3);
  std::vector<Point> uv = identity_uvs(mesh);
  const std::vector<Point> start = uv;
  const UvUntangling u = untangle_uvs(mesh, uv, held_vertices(), kPositive);
  EXPECT_EQ(u.rejected_before, 0);
  EXPECT_EQ(u.rounds, 0);
  EXPECT_FALSE(u.applied);
  EXPECT_EQ(uv, start);
}

TEST(UvUntangling, ACancelledRunLeavesTheUvsUnchanged) {
  const TriangleMesh mesh = testing::flat_grid(kGrid, kGrid);
  std::vector<Point> uv = identity_uvs(mesh);
  uv[vertex(5, 5)] = Point(8.0 * 7.5, 8.0 * 5.2);
  const std::vector<Point> start = uv;
  ASSERT_GT(negative_faces(mesh, uv), 0);
  std::atomic<bool> cancel{true};
  RunControl control;
  control.cancel = &cancel;
  EXPECT_THROW(untangle_uvs(mesh, uv, held_vertices(), kPositive, {}, control), CanceledError);
  EXPECT_EQ(uv, start);
}

}  // namespace
}  // namespace texwarp::mesh
