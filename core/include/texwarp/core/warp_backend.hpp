// WarpBackend: the small interface every compute backend implements (CPU reference, OpenCL): move points
// along the field's pathlines, and inverse-map a whole output pixel grid. Tests hold backends to the CPU one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "texwarp/core/pathline.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

class WarpBackend {
 public:
  virtual ~WarpBackend() = default;
  virtual std::string name() const = 0;

  // Applies segment k's W_k (kForward) or W_k⁻¹ (kInverse) to every point in place: pathlines of that segment's
  // field over its local unit time, no pre-alignment.
  virtual void flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                            Direction direction, const RunControl& control) = 0;

  // Like flow_segment, also giving W_k's Jacobian at each starting point: the variational equation
  // dJ/dt = ∇v·J integrated along each pathline (both backends).
  virtual void flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                          std::span<FlowJacobian> jacobians, Direction direction,
                                          const RunControl& control) = 0;

  // Applies W = W_{K−1} ∘ … ∘ W_0 (kForward) or W⁻¹ (kInverse, segments K−1 … 0) to every point in place:
  // pathlines only, no pre-alignment. Progress is split evenly over the segments.
  void flow_points(const WarpProblem& problem, std::span<Point> points, Direction direction, const RunControl& control);

  // Like flow_points, also giving the flow's Jacobian at each starting point, chained over the segments
  // (J = J_k·J_previous).
  void flow_points_with_jacobian(const WarpProblem& problem, std::span<Point> points, std::span<FlowJacobian> jacobians,
                                 Direction direction, const RunControl& control);

  // Source position f⁻¹(c) of every output pixel centre c = (x + 0.5, y + 0.5), row-major, width·height
  // entries, pre-alignment included. The default runs flow_points over rows.
  virtual std::vector<Point> inverse_map_grid(const WarpProblem& problem, int width, int height,
                                              const RunControl& control);

  // Calls run again in double since the backend was made, because float32's pathline steps collapsed (the OpenCL
  // backend under its automatic precision); 0 for a backend that computes in double. A job reports the difference.
  virtual std::uint64_t double_retries() const { return 0; }
};

// f (kForward) or f⁻¹ (kInverse) of points in place, pre-alignment included: f = W ∘ S.
void map_points(WarpBackend& backend, const WarpProblem& problem, std::span<Point> points, Direction direction,
                const RunControl& control = {});

// The same with the map's Jacobian at each starting point (chain rule through S).
void map_points_with_jacobian(WarpBackend& backend, const WarpProblem& problem, std::span<Point> points,
                              std::span<FlowJacobian> jacobians, Direction direction, const RunControl& control = {});

}  // namespace texwarp
