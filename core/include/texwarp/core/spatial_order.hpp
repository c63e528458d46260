// Points in Morton (Z) order: the order in which batches of pathlines are grouped, so that the points that share
// a work-item (and its step sequence) lie close together.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp {

// Indices of `points` sorted by the Morton code of their positions (quantised to 16 bits per axis over their
// bounding square; ties keep their order). Points that are not finite sort first.
std::vector<std::size_t> spatial_order(std::span<const Point> points);

}  // namespace texwarp
