// Placing a planar embedding (y up) into a texture frame in pixels (y down, DESIGN.md §3): optionally rotated
// to fill the frame best, mirrored in y so that faces seen from the front stay counter-clockwise in UV space,
// uniformly scaled (aspect kept) and centred inside a margin.
#pragma once

#include <span>
#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp::mesh {

struct FramePlacementOptions {
  int width = 0;  // frame size in pixels
  int height = 0;
  double margin_px = 8.0;  // free band on every side
  // Rotate to the largest scale that fits: candidates are the rotations that lay an edge of the convex hull
  // along either side of the frame (the smallest bounding rectangles have a side on a hull edge).
  bool rotate_to_fit = true;
};

struct FramePlacement {
  std::vector<Point> pixels;     // per vertex, frame pixels
  double pixels_per_unit = 0.0;  // scale: frame pixels per embedding unit
  double rotation_rad = 0.0;     // rotation applied before the mirror
};

// InputError when the frame is empty or the margin leaves no room; the embedding must have non-zero extent.
FramePlacement place_in_frame(std::span<const Point> embedding, const FramePlacementOptions& options);

}  // namespace texwarp::mesh
