// Constraint residuals |f(P_i) − Q_i|: see constraint_residuals.hpp.
#include "texwarp/core/constraint_residuals.hpp"

#include <algorithm>

namespace texwarp {

ConstraintResiduals constraint_residuals(WarpBackend& backend, const WarpProblem& problem, const RunControl& control) {
  std::vector<Point> points;
  points.reserve(problem.size());
  for (const Feature& f : problem.features()) points.push_back(f.source);
  map_points(backend, problem, points, Direction::kForward, control);
  ConstraintResiduals r;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double d = std::abs(points[i] - problem.features()[i].target);
    r.per_feature.push_back(d);
    r.max = std::max(r.max, d);
  }
  return r;
}

}  // namespace texwarp
