// The growth of errors along a chain of trajectory segments, measured on a probe grid: see flow_growth.hpp.
#include "texwarp/core/flow_growth.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/pathline.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {
namespace {

// Where the direction's pathlines start, in flow space: the trajectories' starts of the first segment (forward) or
// their ends in the last (inverse).
std::vector<Point> starts(const WarpProblem& problem, Direction direction) {
  std::vector<Point> out;
  const TrajectorySegment& s =
      direction == Direction::kForward ? problem.segments().front() : problem.segments().back();
  const bool at_end = direction == Direction::kInverse;
  for (const PositionalTrajectory& p : s.positional) out.push_back(at_end ? p.start + p.velocity : p.start);
  for (const GradientTrajectory& g : s.gradient) out.push_back(at_end ? g.start + g.velocity : g.start);
  return out;
}

}  // namespace

std::vector<Point> growth_probe_points(const WarpProblem& problem, Direction direction) {
  const std::vector<Point> around = starts(problem, direction);
  double x0 = std::numeric_limits<double>::infinity();
  double y0 = x0;
  double x1 = -x0;
  double y1 = -x0;
  for (const Point& p : around) {
    x0 = std::min(x0, p.real());
    x1 = std::max(x1, p.real());
    y0 = std::min(y0, p.imag());
    y1 = std::max(y1, p.imag());
  }
  const double margin = kGrowthProbeMargin * std::max({x1 - x0, y1 - y0, 1.0});
  x0 -= margin;
  x1 += margin;
  y0 -= margin;
  y1 += margin;
  std::vector<Point> grid;
  for (int j = 0; j < kGrowthProbeSide; ++j) {
    for (int i = 0; i < kGrowthProbeSide; ++i) {
      grid.emplace_back(x0 + (x1 - x0) * (i + 0.5) / kGrowthProbeSide, y0 + (y1 - y0) * (j + 0.5) / kGrowthProbeSide);
    }
  }
  return grid;
}

double measure_growth_scale(WarpBackend& backend, const WarpProblem& problem, Direction direction,
                            const RunControl& control) {
  const std::size_t k = problem.segments().size();
  if (k < 2 || problem.field_is_zero()) return 1.0;
  RunControl quiet = control;
  quiet.progress = nullptr;
  std::vector<Point> points = growth_probe_points(problem, direction);
  std::vector<FlowJacobian> jacobians(points.size());
  std::vector<double> growth(points.size(), 0.0);
  for (std::size_t step = 0; step < k; ++step) {
    const std::size_t segment = direction == Direction::kForward ? step : k - 1 - step;
    if (problem.segments()[segment].field_is_zero) continue;
    backend.flow_segment_with_jacobian(problem, segment, points, jacobians, direction, quiet);
    for (std::size_t i = 0; i < points.size(); ++i) {
      growth[i] = chain_growth_step(growth[i], largest_singular_value(jacobians[i]));
    }
  }
  double worst = 0.0;
  for (const double g : growth) worst = std::isfinite(g) ? std::max(worst, g) : std::numeric_limits<double>::infinity();
  const double room = 1.0 / kLocalErrorFraction;
  return worst <= room ? 1.0 : std::max(kMinGrowthScale, room / worst);
}

void ensure_growth_scale(WarpBackend& backend, const WarpProblem& problem, Direction direction,
                         const RunControl& control) {
  if (problem.segments().size() < 2) return;
  FlowGrowthCache& cache = problem.growth_cache();
  const auto d = static_cast<std::size_t>(direction == Direction::kForward ? 0 : 1);
  std::call_once(cache.measured[d],
                 [&] { cache.scale[d].store(measure_growth_scale(backend, problem, direction, control)); });
}

}  // namespace texwarp
