// Geometry of one triangle in 3D: area, normal, barycentric interpolation, and the closest point of the
// triangle to a query point (Ericson, Real-Time Collision Detection, 5.1.5), in world units.
#pragma once

#include <array>

#include "texwarp/mesh/vec3.hpp"

namespace texwarp::mesh {

using Barycentric = std::array<double, 3>;  // weights of the corners, summing to 1

// (b − a) × (c − a): length twice the area, direction the front normal.
inline Vec3 doubled_normal(Vec3 a, Vec3 b, Vec3 c) { return cross(b - a, c - a); }
inline double triangle_area(Vec3 a, Vec3 b, Vec3 c) { return 0.5 * norm(doubled_normal(a, b, c)); }
inline Vec3 interpolate(Vec3 a, Vec3 b, Vec3 c, const Barycentric& w) { return w[0] * a + w[1] * b + w[2] * c; }

struct ClosestPoint {
  Vec3 point;
  Barycentric barycentric;
  double distance = 0.0;
};

// Closest point of the (non-degenerate) triangle abc to p.
ClosestPoint closest_point_on_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c);

}  // namespace texwarp::mesh
