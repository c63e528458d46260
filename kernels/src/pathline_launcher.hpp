// PathlineLauncher: runs the flow_pathlines kernel (kernels/cl/pathline.cl), optionally with the flow's Jacobian
// (TW_JACOBIAN), over work-items of kPointsPerItem points, in the tiles of a TilePlan, two in flight
// (DoubleBuffer); progress is reported and cancellation checked between tiles.
#pragma once

#include <cstddef>
#include <functional>

#include "kernel_contract.hpp"
#include "opencl_device.hpp"
#include "texwarp/core/pathline.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp::kernels_detail {

template <class Real>
struct TileData {
  std::size_t first = 0;  // first work-item of the tile
  std::size_t count = 0;  // work-items in the tile
  // kPointsPerItem·count each; point k of item i at (i − first)·kPointsPerItem + k.
  Real* origin_x = nullptr;
  Real* origin_y = nullptr;
  Real* offset_x = nullptr;  // start offsets on fill, end offsets on take
  Real* offset_y = nullptr;
  const int* evaluations = nullptr;  // per item, on take
  // With the Jacobian, on take: kJacobianComponents·kPointsPerItem per item, at
  // (i − first)·kJacobianComponents·kPointsPerItem + c·kPointsPerItem + k for component c of point k: ∂x/∂x,
  // ∂y/∂x, ∂x/∂y, ∂y/∂y (end point with respect to start point).
  const Real* jacobians = nullptr;
};

template <class Real>
class PathlineLauncher {
 public:
  // Writes the origins and start offsets of the tile's points (every slot, padding included).
  using Fill = std::function<void(TileData<Real>& tile)>;
  // Reads the end offsets of the tile's points.
  using Take = std::function<void(const TileData<Real>& tile)>;

  // The pathlines of the problem's segment `segment`; with_jacobian: integrate the variational equation too
  // (TileData::jacobians on take).
  PathlineLauncher(const DeviceHandle& device, const WarpProblem& problem, std::size_t segment, Direction direction,
                   bool with_jacobian = false);

  // Integrates `items` work-items. Throws NumericalError (a point's pathline failed), CanceledError, OpenClError.
  void run(std::size_t items, const Fill& fill, const Take& take, const RunControl& control,
           OpenClRunStats& stats) const;

 private:
  const DeviceHandle& device_;
  const WarpProblem& problem_;
  std::size_t segment_;
  Direction direction_;
  bool with_jacobian_;
};

extern template class PathlineLauncher<float>;
extern template class PathlineLauncher<double>;

}  // namespace texwarp::kernels_detail
