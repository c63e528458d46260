// Jacobian statistics of a map sampled on a regular grid: determinants of the discrete (per-triangle)
// Jacobian, their minimum and maximum, and how many are ≤ 0 (a fold or a collapse).
#pragma once

#include <cstddef>
#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp {

struct JacobianStats {
  double min_det = 0.0;
  double max_det = 0.0;
  std::size_t samples = 0;      // triangles measured (two per grid cell)
  std::size_t nonpositive = 0;  // triangles with det ≤ 0
};

// `mapped` holds the map's values at grid nodes (x0 + i·step, y0 + j·step), nx·ny row-major. Each cell is
// split into two triangles; det is the signed area ratio (1 for the identity).
JacobianStats grid_jacobian_stats(const std::vector<Point>& mapped, int nx, int ny, double step);

}  // namespace texwarp
