// Triangulation of one polygonal face (an OBJ quad or n-gon) by ear clipping in the polygon's best-fit plane
// (Newell's normal): convex polygons and non-convex planar ones alike, keeping the polygon's orientation.
#pragma once

#include <span>
#include <vector>

#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

// The polygon's n − 2 triangles over its vertex ids (in range of `positions`), each counter-clockwise as the polygon
// is; empty when the polygon has no ear to clip (degenerate: zero area, or self-intersecting in its plane).
std::vector<Face> triangulate_polygon(std::span<const int> polygon, std::span<const Vec3> positions);

}  // namespace texwarp::mesh
