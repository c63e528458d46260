// Default grid inverse map and the pre-aligned point maps: see warp_backend.hpp.
#include "texwarp/core/warp_backend.hpp"

namespace texwarp {

std::vector<Point> WarpBackend::inverse_map_grid(const WarpProblem& problem, int width, int height,
                                                 const RunControl& control) {
  std::vector<Point> grid(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
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
