// Default grid inverse map and the pre-aligned point maps: see warp_backend.hpp.
#include "texwarp/core/warp_backend.hpp"

#include <algorithm>

#include "texwarp/core/flow_growth.hpp"
#include "texwarp/core/image_buffer.hpp"

namespace texwarp {
namespace {

// The segments in the order a flow runs them: 0 … K−1 forward, K−1 … 0 inverse.
std::size_t segment_at(const WarpProblem& problem, std::size_t step, Direction direction) {
  return direction == Direction::kForward ? step : problem.segments().size() - 1 - step;
}

// The control of step `step` of `steps`: its progress maps into [step/steps, (step+1)/steps].
RunControl segment_control(const RunControl& control, std::size_t step, std::size_t steps) {
  RunControl c = control;
  if (control.progress) {
    const double lo = static_cast<double>(step) / static_cast<double>(steps);
    const double width = 1.0 / static_cast<double>(steps);
    c.progress = [progress = control.progress, lo, width](double f) { progress(lo + width * f); };
  }
  return c;
}

}  // namespace

void WarpBackend::flow_points(const WarpProblem& problem, std::span<Point> points, Direction direction,
                              const RunControl& control) {
  const std::size_t steps = problem.segments().size();
  if (steps == 1) return flow_segment(problem, 0, points, direction, control);
  ensure_growth_scale(*this, problem, direction, control);
  for (std::size_t step = 0; step < steps; ++step) {
    flow_segment(problem, segment_at(problem, step, direction), points, direction,
                 segment_control(control, step, steps));
  }
}

void WarpBackend::flow_points_with_jacobian(const WarpProblem& problem, std::span<Point> points,
                                            std::span<FlowJacobian> jacobians, Direction direction,
                                            const RunControl& control) {
  const std::size_t steps = problem.segments().size();
  if (steps == 1) return flow_segment_with_jacobian(problem, 0, points, jacobians, direction, control);
  ensure_growth_scale(*this, problem, direction, control);
  std::vector<FlowJacobian> total(jacobians.size());
  for (std::size_t step = 0; step < steps; ++step) {
    flow_segment_with_jacobian(problem, segment_at(problem, step, direction), points, jacobians, direction,
                               segment_control(control, step, steps));
    // J = J_k·J_previous, column by column: J_k applied to each column of the product so far.
    for (std::size_t i = 0; i < total.size() && i < jacobians.size(); ++i) {
      const FlowJacobian& k = jacobians[i];
      const FlowJacobian& p = total[i];
      total[i] = FlowJacobian{k.dx * p.dx.real() + k.dy * p.dx.imag(), k.dx * p.dy.real() + k.dy * p.dy.imag()};
    }
  }
  std::copy(total.begin(), total.end(), jacobians.begin());
}

std::vector<Point> WarpBackend::inverse_map_grid(const WarpProblem& problem, int width, int height,
                                                 const RunControl& control) {
  std::vector<Point> grid = huge_page_vector<Point>(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      grid[static_cast<std::size_t>(y) * width + x] = Point(x + 0.5, y + 0.5);
    }
  }
  map_points(*this, problem, grid, Direction::kInverse, control);
  return grid;
}

void map_points_with_jacobian(WarpBackend& backend, const WarpProblem& problem, std::span<Point> points,
                              std::span<FlowJacobian> jacobians, Direction direction, const RunControl& control) {
  const Similarity& s = problem.prealignment();
  if (direction == Direction::kForward) {
    for (Point& p : points) p = s(p);
    backend.flow_points_with_jacobian(problem, points, jacobians, direction, control);
    // D(W∘S) = DW·DS, DS the multiplication by a: columns DW·(a) and DW·(i·a).
    const Point a = s.a;
    for (FlowJacobian& j : jacobians) {
      j = FlowJacobian{j.dx * a.real() + j.dy * a.imag(), -j.dx * a.imag() + j.dy * a.real()};
    }
  } else {
    backend.flow_points_with_jacobian(problem, points, jacobians, direction, control);
    const Similarity inv = s.inverse();
    for (Point& p : points) p = inv(p);
    for (FlowJacobian& j : jacobians) j = FlowJacobian{inv.a * j.dx, inv.a * j.dy};
  }
}

void map_points(WarpBackend& backend, const WarpProblem& problem, std::span<Point> points, Direction direction,
                const RunControl& control) {
  const Similarity& s = problem.prealignment();
  if (direction == Direction::kForward) {
    for (Point& p : points) p = s(p);
    backend.flow_points(problem, points, direction, control);
  } else {
    backend.flow_points(problem, points, direction, control);
    const Similarity inv = s.inverse();
    for (Point& p : points) p = inv(p);
  }
}

}  // namespace texwarp
