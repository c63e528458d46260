// Constraint residuals of a warp: |f(P_i) − Q_i| for every feature, in output pixels.
#pragma once

#include <vector>

#include "texwarp/core/run_control.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

struct ConstraintResiduals {
  std::vector<double> per_feature;  // in input order
  double max = 0.0;
};

ConstraintResiduals constraint_residuals(WarpBackend& backend, const WarpProblem& problem,
                                         const RunControl& control = {});

}  // namespace texwarp
