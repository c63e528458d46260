// The independent reference the certified-lattice tests hold grids against: the CPU backend's per-pixel pathlines
// of the same features at a far tighter integration tolerance.
#pragma once

#include <vector>

#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp::testing {

// f⁻¹ at every pixel centre of a width × height grid, by the CPU reference integrated to `tolerance_px`.
inline std::vector<Point> reference_inverse_grid(const WarpProblem& problem, int width, int height,
                                                 double tolerance_px) {
  WarpOptions tight = problem.options();
  tight.tolerance_px = tolerance_px;
  CpuBackend cpu;
  return cpu.inverse_map_grid(WarpProblem(problem.features(), tight), width, height, {});
}

}  // namespace texwarp::testing
