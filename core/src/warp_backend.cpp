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

namespace {

// Step of the default Jacobian's central differences, pixels.
constexpr double kDifferenceStepPx = 1e-2;

}  // namespace

void WarpBackend::flow_points_with_jacobian(const WarpProblem& problem, std::span<Point> points,
                                            std::span<FlowJacobian> jacobians, Direction direction,
                                            const RunControl& control) {
  std::vector<Point> probes;
  probes.reserve(5 * points.size());
  for (const Point p : points) {
    for (const Point d : {Point(0.0), Point(kDifferenceStepPx, 0.0), Point(-kDifferenceStepPx, 0.0),
                          Point(0.0, kDifferenceStepPx), Point(0.0, -kDifferenceStepPx)}) {
      probes.push_back(p + d);
    }
  }
  flow_points(problem, probes, direction, control);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Point* q = probes.data() + 5 * i;
    points[i] = q[0];
    jacobians[i] = FlowJacobian{(q[1] - q[2]) / (2.0 * kDifferenceStepPx), (q[3] - q[4]) / (2.0 * kDifferenceStepPx)};
  }
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
