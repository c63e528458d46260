// CpuBackend: the double-precision reference backend: pathlines integrated on the CPU, batches of points in
// parallel over threads. Everything else is checked against it.
#pragma once

#include "texwarp/core/warp_backend.hpp"

namespace texwarp {

class CpuBackend final : public WarpBackend {
 public:
  std::string name() const override { return "cpu"; }
  void flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points, Direction direction,
                    const RunControl& control) override;
  void flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                  std::span<FlowJacobian> jacobians, Direction direction,
                                  const RunControl& control) override;
};

}  // namespace texwarp
