// Free-boundary LSCM: a flat mesh comes back as a similarity of itself, a developable strip isometric up to
// scale, and the energy it reports matches an independent evaluation and is a minimum.
#include <cmath>
#include <complex>
#include <random>

#include <gtest/gtest.h>

#include "mesh_test_shapes.hpp"
#include "texwarp/mesh/lscm.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"

namespace texwarp::mesh {
namespace {

// Independent conformal energy: per triangle the 2×2 Jacobian J of the map from the triangle's own 2D frame
// (built here from edge lengths and the law of cosines) to the plane; E = Σ A (|J|_F² − 2 det J).
double reference_energy(const TriangleMesh& m, const std::vector<Point>& uv) {
  double e = 0.0;
  for (const Face& f : m.faces) {
    const Vec3 p0 = m.vertices[f[0]], p1 = m.vertices[f[1]], p2 = m.vertices[f[2]];
    const double a = norm(p1 - p0), b = norm(p2 - p0), c = norm(p2 - p1);
    const double cx = (a * a + b * b - c * c) / (2 * a);
    const double cy = std::sqrt(std::max(0.0, b * b - cx * cx));
    // Local edges E = [(a, 0), (cx, cy)] (columns), image edges F = [uv1 − uv0, uv2 − uv0]; J = F·E⁻¹.
    const Point f1 = uv[f[1]] - uv[f[0]], f2 = uv[f[2]] - uv[f[0]];
    const double det_e = a * cy;
    // E⁻¹ = [[cy, −cx], [0, a]] / det_e
    const double j11 = (f1.real() * cy) / det_e, j12 = (-f1.real() * cx + f2.real() * a) / det_e;
    const double j21 = (f1.imag() * cy) / det_e, j22 = (-f1.imag() * cx + f2.imag() * a) / det_e;
    const double area = 0.5 * a * cy;
    e += area * (j11 * j11 + j12 * j12 + j21 * j21 + j22 * j22 - 2.0 * (j11 * j22 - j12 * j21));
  }
  return e;
}

// Rigid motion of 3D space (rotation about a tilted axis and a shift).
Vec3 move(Vec3 p) {
  const double c = std::cos(0.7), s = std::sin(0.7);
  const Vec3 q{c * p.x - s * p.z, p.y, s * p.x + c * p.z};  // about y
  const double c2 = std::cos(-0.4), s2 = std::sin(-0.4);
  return Vec3{q.x, c2 * q.y - s2 * q.z, s2 * q.y + c2 * q.z} + Vec3{3.0, -1.0, 2.0};  // about x, then shift
}

TEST(Lscm, FlatMeshComesBackAsASimilarityOfItself) {
  TriangleMesh flat = testing::flat_grid(12, 9, 0.1, 0.3, 7);
  std::vector<Point> original;
  for (const Vec3& v : flat.vertices) original.emplace_back(v.x, v.y);
  for (Vec3& v : flat.vertices) v = move(v);
  const MeshRegion r = whole_mesh_region(flat, proto::InputLocation::file("flat"));
  const LscmEmbedding e = lscm_embedding(r.local, r.boundary);
  // Least-squares similarity z ↦ a·z + b from the original plane coordinates onto the embedding.
  Point mz(0, 0), mw(0, 0);
  for (std::size_t i = 0; i < original.size(); ++i) {
    mz += original[i];
    mw += e.positions[i];
  }
  mz /= double(original.size());
  mw /= double(original.size());
  Point num(0, 0);
  double den = 0.0;
  for (std::size_t i = 0; i < original.size(); ++i) {
    num += std::conj(original[i] - mz) * (e.positions[i] - mw);
    den += std::norm(original[i] - mz);
  }
  const Point a = num / den;
  double worst = 0.0;
  for (std::size_t i = 0; i < original.size(); ++i)
    worst = std::max(worst, std::abs(a * (original[i] - mz) + mw - e.positions[i]));
  EXPECT_LT(worst, 1e-10);
  EXPECT_NEAR(std::abs(a), 1.0, 1e-9);  // pins at their 3D distance: the scale is 1
  // Zero up to rounding: positions within 1e-10 of the similarity leave an energy of order 1e-18 (CHOLMOD's
  // supernodal factor rounds differently from a simplicial one: 1.8e-18 here).
  EXPECT_LT(e.energy, 1e-16);
  EXPECT_LT(reference_energy(r.local, e.positions), 1e-16);
}

TEST(Lscm, DevelopableStripIsIsometricUpToScale) {
  const TriangleMesh strip = testing::cylinder_strip(1.0, 2.5, 1.5, 24, 10);
  const MeshRegion r = whole_mesh_region(strip, proto::InputLocation::file("strip"));
  const LscmEmbedding e = lscm_embedding(r.local, r.boundary);
  double lo = 1e300, hi = 0.0;
  for (const Face& f : r.local.faces) {
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      const double ratio = std::abs(e.positions[a] - e.positions[b]) / norm(r.local.vertices[a] - r.local.vertices[b]);
      lo = std::min(lo, ratio);
      hi = std::max(hi, ratio);
    }
  }
  EXPECT_LT(hi / lo - 1.0, 1e-9);
  // Every triangle keeps its orientation.
  for (const Face& f : r.local.faces) {
    const Point u = e.positions[f[1]] - e.positions[f[0]], v = e.positions[f[2]] - e.positions[f[0]];
    EXPECT_GT(u.real() * v.imag() - u.imag() * v.real(), 0.0);
  }
}

TEST(Lscm, EnergyMatchesAnIndependentEvaluationAndIsAMinimum) {
  const TriangleMesh cap = testing::sphere_cap(1.3, 8, 20);  // not developable: E > 0
  const MeshRegion r = whole_mesh_region(cap, proto::InputLocation::file("cap"));
  const LscmEmbedding e = lscm_embedding(r.local, r.boundary);
  const double reference = reference_energy(r.local, e.positions);
  EXPECT_GT(reference, 1e-4);
  EXPECT_NEAR(e.energy, reference, 1e-10 * reference);
  EXPECT_NEAR(lscm_energy(r.local, e.positions), reference, 1e-10 * reference);
  // The pins: boundary vertices at 0 and at their 3D distance on the x axis.
  const auto [p0, p1] = e.pinned;
  EXPECT_EQ(e.positions[p0], Point(0.0, 0.0));
  EXPECT_NEAR(e.positions[p1].real(), norm(r.local.vertices[p1] - r.local.vertices[p0]), 1e-15);
  EXPECT_EQ(e.positions[p1].imag(), 0.0);
  EXPECT_NE(std::find(r.boundary.begin(), r.boundary.end(), p0), r.boundary.end());
  EXPECT_NE(std::find(r.boundary.begin(), r.boundary.end(), p1), r.boundary.end());
  // Moving the free vertices at random never lowers the energy (a least-squares minimum).
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1e-3);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Point> moved = e.positions;
    for (int v = 0; v < r.local.vertex_count(); ++v) {
      if (v != p0 && v != p1) moved[v] += Point(n(rng), n(rng));
    }
    EXPECT_GT(reference_energy(r.local, moved), reference);
  }
  // A bijective cap: no triangle flips.
  for (const Face& f : r.local.faces) {
    const Point u = e.positions[f[1]] - e.positions[f[0]], v = e.positions[f[2]] - e.positions[f[0]];
    EXPECT_GT(u.real() * v.imag() - u.imag() * v.real(), 0.0);
  }
}

TEST(Lscm, PinnedVerticesAreFarApart) {
  const TriangleMesh grid = testing::flat_grid(10, 3);
  const MeshRegion r = whole_mesh_region(grid, proto::InputLocation::file("g"));
  const auto pins = lscm_pin_vertices(r.local, r.boundary);
  // The farthest boundary pair of a 10×3 rectangle is a pair of opposite corners: distance √109.
  EXPECT_NEAR(norm(r.local.vertices[pins[0]] - r.local.vertices[pins[1]]), std::sqrt(109.0), 1e-12);
}

}  // namespace
}  // namespace texwarp::mesh
