// Ear clipping of one polygonal face: see polygon_triangulation.hpp.
#include "texwarp/mesh/polygon_triangulation.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace texwarp::mesh {
namespace {

struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

double orient(Point2 a, Point2 b, Point2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

// p inside or on the triangle abc (counter-clockwise).
bool in_triangle(Point2 p, Point2 a, Point2 b, Point2 c) {
  return orient(a, b, p) >= 0.0 && orient(b, c, p) >= 0.0 && orient(c, a, p) >= 0.0;
}

}  // namespace

std::vector<Face> triangulate_polygon(std::span<const int> polygon, std::span<const Vec3> positions) {
  const std::size_t n = polygon.size();
  if (n < 3) return {};
  if (n == 3) return {Face{polygon[0], polygon[1], polygon[2]}};
  // Newell's normal: the polygon's orientation and best-fit plane, robust for non-convex and slightly warped faces.
  Vec3 normal;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a = positions[polygon[i]];
    const Vec3 b = positions[polygon[(i + 1) % n]];
    normal = normal + Vec3{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
  }
  const double length = norm(normal);
  if (!(length > 0.0) || !std::isfinite(length)) return {};
  normal = normal / length;
  // An in-plane basis (u, v) with u × v = normal: the polygon is counter-clockwise in it.
  const Vec3 helper = std::abs(normal.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 u = cross(helper, normal) / norm(cross(helper, normal));
  const Vec3 v = cross(normal, u);
  std::vector<Point2> p(n);
  double extent = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 q = positions[polygon[i]] - positions[polygon[0]];
    p[i] = {dot(q, u), dot(q, v)};
    extent = std::max({extent, std::abs(p[i].x), std::abs(p[i].y)});
  }
  // A corner counts as convex when its doubled area exceeds this (relative to the polygon's size).
  const double min_area = 1e-14 * extent * extent;
  // Strictly convex (the usual quad or n-gon): a fan from vertex 0, in O(n).
  bool convex = true;
  for (std::size_t i = 0; i < n && convex; ++i) convex = orient(p[(i + n - 1) % n], p[i], p[(i + 1) % n]) > min_area;
  if (convex) {
    std::vector<Face> fan;
    for (std::size_t i = 1; i + 1 < n; ++i) fan.push_back({polygon[0], polygon[i], polygon[i + 1]});
    return fan;
  }
  if (n > kMaxEarClippingVertices) return {};
  std::vector<std::size_t> left(n);
  for (std::size_t i = 0; i < n; ++i) left[i] = i;
  std::vector<Face> triangles;
  triangles.reserve(n - 2);
  while (left.size() > 3) {
    const std::size_t m = left.size();
    bool clipped = false;
    for (std::size_t k = 0; k < m && !clipped; ++k) {
      const std::size_t a = left[(k + m - 1) % m];
      const std::size_t b = left[k];
      const std::size_t c = left[(k + 1) % m];
      if (orient(p[a], p[b], p[c]) <= min_area) continue;  // reflex or flat corner
      bool empty = true;
      for (const std::size_t o : left) {
        if (o == a || o == b || o == c) continue;
        if (in_triangle(p[o], p[a], p[b], p[c])) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      triangles.push_back({polygon[a], polygon[b], polygon[c]});
      left.erase(left.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
    }
    if (!clipped) return {};
  }
  if (orient(p[left[0]], p[left[1]], p[left[2]]) <= min_area) return {};
  triangles.push_back({polygon[left[0]], polygon[left[1]], polygon[left[2]]});
  return triangles;
}

}  // namespace texwarp::mesh
