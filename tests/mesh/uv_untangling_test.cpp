// Untangling (core/mesh/uv_untangling.hpp): a fold of free vertices is unfolded with the held vertices bit for bit
// where they were; a triangle whose corners are all held stays as it is and nothing is made worse; a flip-free map
// is left alone; cancellation leaves the UVs unchanged. Orientation is checked here from signed areas, independently
// of the library's checks.
#include <algorithm>
#include <atomic>
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
