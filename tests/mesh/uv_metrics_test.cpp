// L² stretch (Sander et al. 2001) and shear (ABF++) on single triangles against values computed by hand,
// the area normalisation, flips and degenerate triangles, and the area-weighted mesh norm.
#include <cmath>

#include <gtest/gtest.h>

#include "texwarp/mesh/uv_metrics.hpp"

namespace texwarp::mesh {
namespace {

const Vec3 kQ0{0, 0, 0}, kQ1{1, 0, 0}, kQ2{0, 1, 0};

// UVs given by a linear map (m11 m12; m21 m22) of the triangle's own xy coordinates.
std::array<Point, 3> mapped(double m11, double m12, double m21, double m22) {
  auto f = [&](Vec3 q) { return Point(m11 * q.x + m12 * q.y, m21 * q.x + m22 * q.y); };
  return {f(kQ0), f(kQ1), f(kQ2)};
}

TriangleMesh one_triangle() {
  TriangleMesh m;
  m.vertices = {kQ0, kQ1, kQ2};
  m.faces = {{0, 1, 2}};
  return m;
}

TEST(TriangleDistortion, IdentityHasStretchOneAndNoShear) {
  const auto uv = mapped(1, 0, 0, 1);
  const TriangleDistortion d = triangle_distortion(kQ0, kQ1, kQ2, uv[0], uv[1], uv[2]);
  EXPECT_DOUBLE_EQ(d.l2_stretch, 1.0);
  EXPECT_DOUBLE_EQ(d.linf_stretch, 1.0);
  EXPECT_DOUBLE_EQ(d.shear, 0.0);
  EXPECT_DOUBLE_EQ(d.uv_area, 0.5);
  EXPECT_DOUBLE_EQ(d.surface_area, 0.5);
  EXPECT_FALSE(d.flipped);
  EXPECT_FALSE(d.degenerate);
}

TEST(TriangleDistortion, AxisScalingByHand) {
  // uv = (2x, y): S = (uv → surface) = diag(1/2, 1): S_s = (1/2, 0, 0), S_t = (0, 1, 0);
  // a = 1/4, b = 0, c = 1: L² = √((1/4 + 1)/2) = √0.625, Γ = 1, shear 0.
  const auto uv = mapped(2, 0, 0, 1);
  const TriangleDistortion d = triangle_distortion(kQ0, kQ1, kQ2, uv[0], uv[1], uv[2]);
  EXPECT_NEAR(d.l2_stretch, std::sqrt(0.625), 1e-15);
  EXPECT_NEAR(d.linf_stretch, 1.0, 1e-15);
  EXPECT_NEAR(d.shear, 0.0, 1e-15);
  // Mesh norm: the domain is scaled by 1/√2 (its area 1 → 1/2, the surface's): S scales by √2: a = 1/2,
  // c = 2: L² = √1.25, Γ = √2.
  const UvMetrics m = uv_metrics(one_triangle(), uv);
  EXPECT_NEAR(m.l2_stretch, std::sqrt(1.25), 1e-14);
  EXPECT_NEAR(m.linf_stretch, std::sqrt(2.0), 1e-14);
  EXPECT_NEAR(m.l2_shear, 0.0, 1e-15);
  EXPECT_EQ(m.flipped, 0);
}

TEST(TriangleDistortion, ShearByHand) {
  // uv = (x + k·y, y): S = [[1, −k], [0, 1]]: S_s = (1, 0, 0), S_t = (−k, 1, 0); a = 1, b = −k, c = 1 + k².
  const double k = 0.5;
  const auto uv = mapped(1, k, 0, 1);
  const TriangleDistortion d = triangle_distortion(kQ0, kQ1, kQ2, uv[0], uv[1], uv[2]);
  const double a = 1, b = -k, c = 1 + k * k;
  EXPECT_NEAR(d.l2_stretch, std::sqrt((a + c) / 2), 1e-15);
  EXPECT_NEAR(d.linf_stretch, std::sqrt(((a + c) + std::sqrt((a - c) * (a - c) + 4 * b * b)) / 2), 1e-15);
  EXPECT_NEAR(d.shear, k / std::sqrt(1 + k * k), 1e-15);  // cos of the angle between S_s and S_t
  // Area-preserving: the normalised mesh values are the same.
  const UvMetrics m = uv_metrics(one_triangle(), uv);
  EXPECT_NEAR(m.l2_stretch, d.l2_stretch, 1e-14);
  EXPECT_NEAR(m.l2_shear, d.shear, 1e-14);
}

TEST(TriangleDistortion, SimilaritiesAreFreeOfDistortionAfterNormalisation) {
  // uv = 3·R(40°)·xy: raw stretch 1/3, normalised 1; shear 0.
  const double c = 3 * std::cos(0.7), s = 3 * std::sin(0.7);
  const auto uv = mapped(c, -s, s, c);
  const TriangleDistortion d = triangle_distortion(kQ0, kQ1, kQ2, uv[0], uv[1], uv[2]);
  EXPECT_NEAR(d.l2_stretch, 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(d.shear, 0.0, 1e-15);
  const UvMetrics m = uv_metrics(one_triangle(), uv);
  EXPECT_NEAR(m.l2_stretch, 1.0, 1e-14);
  EXPECT_NEAR(m.linf_stretch, 1.0, 1e-14);
  EXPECT_NEAR(m.l2_shear, 0.0, 1e-15);
}

TEST(TriangleDistortion, TiltedTriangleFlattenedIsometrically) {
  // A triangle in 3D, its UVs its own edge lengths laid flat: stretch 1, shear 0.
  const Vec3 q0{1, 2, 3}, q1{2, 2.5, 3.5}, q2{0.5, 3, 4};
  const double a = norm(q1 - q0), b = norm(q2 - q0), cc = norm(q2 - q1);
  const double cx = (a * a + b * b - cc * cc) / (2 * a);
  const Point u0(0, 0), u1(a, 0), u2(cx, std::sqrt(b * b - cx * cx));
  const TriangleDistortion d = triangle_distortion(q0, q1, q2, u0, u1, u2);
  EXPECT_NEAR(d.l2_stretch, 1.0, 1e-14);
  EXPECT_NEAR(d.linf_stretch, 1.0, 1e-14);
  EXPECT_NEAR(d.shear, 0.0, 1e-14);
}

TEST(TriangleDistortion, FlippedAndDegenerateTriangles) {
  const auto mirror = mapped(1, 0, 0, -1);
  const TriangleDistortion f = triangle_distortion(kQ0, kQ1, kQ2, mirror[0], mirror[1], mirror[2]);
  EXPECT_TRUE(f.flipped);
  EXPECT_DOUBLE_EQ(f.uv_area, -0.5);
  EXPECT_DOUBLE_EQ(f.l2_stretch, 1.0);   // the stretch of a mirror image is still 1
  const auto flat = mapped(1, 1, 2, 2);  // rank 1: all on a line
  const TriangleDistortion g = triangle_distortion(kQ0, kQ1, kQ2, flat[0], flat[1], flat[2]);
  EXPECT_TRUE(g.degenerate);
  EXPECT_FALSE(g.flipped);

  TriangleMesh m;
  m.vertices = {kQ0, kQ1, kQ2, {1, 1, 0}, {2, 0, 0}};
  m.faces = {{0, 1, 2}, {1, 3, 2}, {1, 4, 3}};
  // Face 1 mirrored (vertex 3 pulled across edge 1–2), face 2 collapsed onto a line.
  const std::vector<Point> uv = {{0, 0}, {1, 0}, {0, 1}, {0.2, 0.2}, {0.6, 0.1}};
  const UvMetrics metrics = uv_metrics(m, uv, true);
  EXPECT_EQ(metrics.flipped, 1);
  EXPECT_EQ(metrics.degenerate, 1);
  EXPECT_TRUE(metrics.per_triangle[1].flipped);
  EXPECT_TRUE(metrics.per_triangle[2].degenerate);
}

TEST(UvMetrics, MeshNormIsAreaWeighted) {
  // Two triangles of surface area 1/2 and 2; UVs: the identity on the first, (2x, y) on the second
  // (per triangle raw L²² = 1 and 0.625). Domain area 1/2 + 4 = 4.5 vs surface 2.5: scale² = 2.5/4.5, so
  // every L²² is multiplied by 4.5/2.5. L²(M)² = (1·0.5 + 0.625·2)/2.5 · 4.5/2.5.
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {10, 0, 0}, {12, 0, 0}, {10, 2, 0}};
  m.faces = {{0, 1, 2}, {3, 4, 5}};
  const std::vector<Point> uv = {{0, 0}, {1, 0}, {0, 1}, {20, 0}, {24, 0}, {20, 2}};
  const UvMetrics metrics = uv_metrics(m, uv);
  const double expected = std::sqrt((1.0 * 0.5 + 0.625 * 2.0) / 2.5 * (4.5 / 2.5));
  EXPECT_NEAR(metrics.l2_stretch, expected, 1e-14);
  EXPECT_NEAR(metrics.surface_area, 2.5, 1e-14);
  EXPECT_NEAR(metrics.uv_area, 4.5, 1e-14);
}

}  // namespace
}  // namespace texwarp::mesh
