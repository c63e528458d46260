// OpenClWarpBackend: pathlines of the warp's field integrated by OpenCL kernels (kernels/cl/*.cl), TW_VECS×16
// points per work-item in explicit vectors; float32 where it meets the tolerance, double below that (and, on a
// device with cl_khr_fp64, for a call whose float32 steps collapsed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "texwarp/core/warp_backend.hpp"
#include "texwarp/kernels/opencl_backend.hpp"

namespace texwarp {

// What the last completed call on a backend did (for benchmarks and logs).
struct OpenClRunStats {
  std::size_t points = 0;             // points integrated (padding excluded)
  std::size_t point_evaluations = 0;  // Σ over points of field evaluations (padding excluded)
  std::size_t launches = 0;           // kernel launches (tiles)
  bool double_precision = false;      // the double kernel ran (tolerance below what float32 holds, or a retry)
  bool retried_in_double = false;     // float32's steps collapsed (kAuto) and the call ran again in double
  double seconds = 0.0;               // wall time of the call
};

class OpenClWarpBackend final : public WarpBackend {
 public:
  // Selects the device (see OpenClOptions); throws OpenClError when none matches.
  explicit OpenClWarpBackend(const OpenClOptions& options = {});
  ~OpenClWarpBackend() override;
  OpenClWarpBackend(const OpenClWarpBackend&) = delete;
  OpenClWarpBackend& operator=(const OpenClWarpBackend&) = delete;

  std::string name() const override { return "opencl"; }
  // "<device name> (<platform name>)".
  std::string device_description() const;

  // Thread-safe: every call has its own kernel objects, queue and buffers. RunControl::threads is not used
  // (PoCL's thread count comes from POCL_MAX_PTHREAD_COUNT); progress and cancellation act between tiles.
  void flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points, Direction direction,
                    const RunControl& control) override;
  std::vector<Point> inverse_map_grid(const WarpProblem& problem, int width, int height,
                                      const RunControl& control) override;
  // The variational equation dJ/dt = ∇v·J (∇v in closed form) integrated along each pathline in the same
  // kernel, J in pixels per pixel of the flow computed (W or W⁻¹, no pre-alignment; FlowJacobian's convention);
  // in double precision where the device has cl_khr_fp64 unless OpenClPrecision::kFloat is asked for.
  void flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                  std::span<FlowJacobian> jacobians, Direction direction,
                                  const RunControl& control) override;

  OpenClRunStats last_run_stats() const;
  std::uint64_t double_retries() const override;

 private:
  // flow_segment with the Jacobians when `jacobians` is not empty (one per point, set to the identity).
  void flow(const WarpProblem& problem, std::size_t segment, std::span<Point> points, std::span<FlowJacobian> jacobians,
            Direction direction, const RunControl& control);

  struct Impl;
  std::unique_ptr<Impl> impl_;
  mutable std::mutex stats_mutex_;
  OpenClRunStats last_stats_;
  std::uint64_t double_retries_ = 0;  // calls with retried_in_double, since construction
};

}  // namespace texwarp
