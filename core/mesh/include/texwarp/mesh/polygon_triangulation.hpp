// Triangulation of one polygonal face (an OBJ quad or n-gon) in the polygon's best-fit plane (Newell's normal): a fan
// for convex polygons, ear clipping for non-convex planar ones, keeping the polygon's orientation.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

// Ear clipping costs O(n³) in the worst case: a polygon that is not strictly convex is clipped only up to this many
// vertices (a hostile file of large non-convex polygons would otherwise cost hours); strictly convex ones are fanned.
inline constexpr std::size_t kMaxEarClippingVertices = 32;

// The polygon's n − 2 triangles over its vertex ids (in range of `positions`), each counter-clockwise as the polygon
// is: a fan when it is strictly convex in its plane, else ear clipping. Empty when the polygon has no ear to clip
// (degenerate: zero area, or self-intersecting in its plane) or is not convex and has over kMaxEarClippingVertices.
std::vector<Face> triangulate_polygon(std::span<const int> polygon, std::span<const Vec3> positions);

}  // namespace texwarp::mesh
