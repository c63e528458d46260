// Closest point on a triangle: see triangle_geometry.hpp.
#include "texwarp/mesh/triangle_geometry.hpp"

namespace texwarp::mesh {
namespace {

ClosestPoint make(Vec3 p, Vec3 a, Vec3 b, Vec3 c, const Barycentric& w) {
  const Vec3 q = interpolate(a, b, c, w);
  return {q, w, norm(p - q)};
}

}  // namespace

ClosestPoint closest_point_on_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  // Voronoi regions of the corners, then of the edges, else the inside (Ericson 2005, §5.1.5).
  const Vec3 ab = b - a;
  const Vec3 ac = c - a;
  const Vec3 ap = p - a;
  const double d1 = dot(ab, ap);
  const double d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return make(p, a, b, c, {1.0, 0.0, 0.0});
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp);
  const double d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return make(p, a, b, c, {0.0, 1.0, 0.0});
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return make(p, a, b, c, {1.0 - v, v, 0.0});
  }
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp);
  const double d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return make(p, a, b, c, {0.0, 0.0, 1.0});
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return make(p, a, b, c, {1.0 - w, 0.0, w});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return make(p, a, b, c, {0.0, 1.0 - w, w});
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom;
  const double w = vc * denom;
  return make(p, a, b, c, {1.0 - v - w, v, w});
}

}  // namespace texwarp::mesh
