// Jacobian determinants (central differences of a closed-form map, the variational equation for the warp) and
// their statistics: see jacobian_stats.hpp.
#include "texwarp/core/jacobian_stats.hpp"

#include <algorithm>
#include <limits>

#include "texwarp/core/spatial_order.hpp"

namespace texwarp {

JacobianStats summarize_determinants(const std::vector<double>& determinants) {
  JacobianStats s;
  s.min_det = std::numeric_limits<double>::infinity();
  s.max_det = -std::numeric_limits<double>::infinity();
  for (const double det : determinants) {
    if (!(det > 0.0)) ++s.nonpositive;  // NaN counts as a fold: it never passes as a valid determinant
    if (det < s.min_det || det != det) s.min_det = det;
    if (det > s.max_det) s.max_det = det;
    ++s.samples;
  }
  return s;
}

std::vector<double> jacobian_determinants(const std::function<void(std::vector<Point>&)>& map,
                                          const std::vector<Point>& points, double h) {
  std::vector<Point> probes;
  probes.reserve(4 * points.size());
  for (const Point p : points) {
    probes.push_back(p + Point(h, 0.0));
    probes.push_back(p - Point(h, 0.0));
    probes.push_back(p + Point(0.0, h));
    probes.push_back(p - Point(0.0, h));
  }
  map(probes);
  std::vector<double> det(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Point dx = (probes[4 * i] - probes[4 * i + 1]) / (2.0 * h);
    const Point dy = (probes[4 * i + 2] - probes[4 * i + 3]) / (2.0 * h);
    det[i] = dx.real() * dy.imag() - dx.imag() * dy.real();
  }
  return det;
}

std::vector<FlowJacobian> warp_jacobians(WarpBackend& backend, const WarpProblem& problem,
                                         const std::vector<Point>& points, Direction direction,
                                         const RunControl& control) {
  const WarpProblem tight = problem.with_tolerance(std::min(problem.tolerance_px(), kJacobianTolerancePx));
  std::vector<FlowJacobian> jacobians(points.size());
  // Blocks of points consecutive in Morton order (compact squares, whose points share work-items in a vector backend
  // as in one call) dealt round-robin into the parts, so that each part samples the whole set and costs about the
  // same.
  const std::vector<std::size_t> order = spatial_order(points);
  const std::size_t blocks = (points.size() + kJacobianBlockPoints - 1) / kJacobianBlockPoints;
  const std::size_t parts = std::clamp<std::size_t>(blocks / kJacobianMinBlocksPerPart, 1, kJacobianParts);
  std::vector<std::size_t> taken;
  std::vector<Point> ends;
  std::vector<FlowJacobian> part_jacobians;
  for (std::size_t part = 0; part < parts; ++part) {
    if (control.canceled()) throw CanceledError();
    taken.clear();
    for (std::size_t b = part; b < blocks; b += parts) {
      const std::size_t end = std::min(points.size(), (b + 1) * kJacobianBlockPoints);
      taken.insert(taken.end(), order.begin() + static_cast<std::ptrdiff_t>(b * kJacobianBlockPoints),
                   order.begin() + static_cast<std::ptrdiff_t>(end));
    }
    ends.clear();
    for (const std::size_t i : taken) ends.push_back(points[i]);
    part_jacobians.assign(ends.size(), FlowJacobian{});
    RunControl part_control = control;
    if (control.progress) {
      part_control.progress = [&control, part, parts](double f) {
        control.progress((static_cast<double>(part) + std::clamp(f, 0.0, 1.0)) / static_cast<double>(parts));
      };
    }
    map_points_with_jacobian(backend, tight, ends, part_jacobians, direction, part_control);
    for (std::size_t k = 0; k < taken.size(); ++k) jacobians[taken[k]] = part_jacobians[k];
    if (control.progress) control.progress(static_cast<double>(part + 1) / static_cast<double>(parts));
  }
  return jacobians;
}

namespace {

// J = p·z + q·z̄ with p = (J₁₁ + J₂₂ + i(J₂₁ − J₁₂))/2, q = (J₁₁ − J₂₂ + i(J₂₁ + J₁₂))/2: σ = |p| ± |q|.
struct ConformalParts {
  double p;  // |p|
  double q;  // |q|
};

ConformalParts conformal_parts(const FlowJacobian& j) {
  return {std::abs(0.5 * Point(j.dx.real() + j.dy.imag(), j.dx.imag() - j.dy.real())),
          std::abs(0.5 * Point(j.dx.real() - j.dy.imag(), j.dx.imag() + j.dy.real()))};
}

}  // namespace

double singular_value_ratio(const FlowJacobian& j) {
  const ConformalParts c = conformal_parts(j);
  const double small = std::abs(c.p - c.q);
  return small > 0.0 ? (c.p + c.q) / small : std::numeric_limits<double>::infinity();
}

double largest_singular_value(const FlowJacobian& j) {
  const ConformalParts c = conformal_parts(j);
  return c.p + c.q;
}

std::vector<double> warp_jacobian_determinants(WarpBackend& backend, const WarpProblem& problem,
                                               const std::vector<Point>& points, Direction direction,
                                               const RunControl& control) {
  const std::vector<FlowJacobian> jacobians = warp_jacobians(backend, problem, points, direction, control);
  std::vector<double> det(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) det[i] = jacobians[i].det();
  return det;
}

}  // namespace texwarp
