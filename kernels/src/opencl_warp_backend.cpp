// The OpenCL backend: points and pixel grids packed into work-items for the pathline kernel: see
// opencl_warp_backend.hpp.
#include "texwarp/kernels/opencl_warp_backend.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "opencl_device.hpp"
#include "pathline_launcher.hpp"
#include "texwarp/core/flow_growth.hpp"
#include "texwarp/core/image_buffer.hpp"
#include "texwarp/core/numerical_error.hpp"
#include "texwarp/core/spatial_order.hpp"
#include "texwarp/kernels/opencl_error.hpp"

namespace texwarp {

using kernels_detail::kJacobianComponents;
using kernels_detail::kLanes;
using kernels_detail::kPointsPerItem;
using kernels_detail::kVectorsPerItem;
using kernels_detail::PathlineLauncher;
using kernels_detail::TileData;

struct OpenClWarpBackend::Impl {
  kernels_detail::DeviceHandle device;
  OpenClPrecision precision;
};

namespace {

// Chosen on the map's tolerance, not the pathlines' (WarpProblem::pathline_tolerance_px): where an inverse map's
// pathlines meet |a|·tolerance, the flow's distances are scaled by |a| too, and with them the float32 offsets each
// point is carried in (beside its own origin) and their rounding. The growth scale of planned segments
// (flow_growth.hpp) shrinks no distance, so a tolerance it takes below float32's floor runs in double where the
// device has it (float32 as before where it has not).
bool needs_double(const WarpProblem& problem, const kernels_detail::DeviceHandle& device, OpenClPrecision precision) {
  if (precision == OpenClPrecision::kFloat) return false;
  const double grown = problem.tolerance_px() *
                       std::min(problem.growth_scale(Direction::kForward), problem.growth_scale(Direction::kInverse));
  if (precision == OpenClPrecision::kAuto && problem.tolerance_px() >= kFloatMinTolerancePx &&
      (grown >= kFloatMinTolerancePx || !device.has_fp64)) {
    return false;
  }
  if (!device.has_fp64) {
    if (precision == OpenClPrecision::kDouble) {
      throw OpenClError("the double-precision kernel needs cl_khr_fp64, which " + device.device_name + " lacks");
    }
    char msg[320];
    std::snprintf(msg, sizeof msg,
                  "tolerance_px %.3g needs the double-precision kernel (float32 holds tolerances ≥ %.3g px), and "
                  "%s has no cl_khr_fp64: raise tolerance_px or use the CPU backend",
                  problem.tolerance_px(), kFloatMinTolerancePx, device.device_name.c_str());
    throw OpenClError(msg);
  }
  return true;
}

// A point in a tile slot: its own origin (rounded to Real) plus the offset that carries the rest.
template <class Real>
void store_point(TileData<Real>& tile, std::size_t at, Point p) {
  tile.origin_x[at] = static_cast<Real>(p.real());
  tile.origin_y[at] = static_cast<Real>(p.imag());
  tile.offset_x[at] = static_cast<Real>(p.real() - static_cast<double>(tile.origin_x[at]));
  tile.offset_y[at] = static_cast<Real>(p.imag() - static_cast<double>(tile.origin_y[at]));
}

template <class Real>
Point load_point(const TileData<Real>& tile, std::size_t at) {
  return {static_cast<double>(tile.origin_x[at]) + static_cast<double>(tile.offset_x[at]),
          static_cast<double>(tile.origin_y[at]) + static_cast<double>(tile.offset_y[at])};
}

// Points in Morton order, kPointsPerItem per work-item; with `jacobians` non-empty (one per point), the
// variational equation too: the flow's Jacobian at each start point.
template <class Real>
void flow_points_with(const kernels_detail::DeviceHandle& device, const WarpProblem& problem, std::size_t segment,
                      std::span<Point> points, std::span<FlowJacobian> jacobians, Direction direction,
                      const RunControl& control, OpenClRunStats& stats) {
  const std::vector<std::size_t> order = spatial_order(points);
  const std::size_t count = points.size();
  const std::size_t items = (count + kPointsPerItem - 1) / kPointsPerItem;
  const bool with_jacobian = !jacobians.empty();
  // Each point is its own origin (rounded to Real); the offset carries the rest.
  auto fill = [&](TileData<Real>& tile) {
    for (std::size_t i = 0; i < tile.count; ++i) {
      for (int k = 0; k < kPointsPerItem; ++k) {
        const std::size_t slot = (tile.first + i) * kPointsPerItem + k;
        const Point p = points[order[std::min(slot, count - 1)]];  // padding repeats the last point
        const std::size_t at = i * kPointsPerItem + k;
        store_point(tile, at, p);
      }
    }
  };
  auto take = [&](const TileData<Real>& tile) {
    for (std::size_t i = 0; i < tile.count; ++i) {
      for (int k = 0; k < kPointsPerItem; ++k) {
        const std::size_t slot = (tile.first + i) * kPointsPerItem + k;
        if (slot >= count) break;
        const std::size_t at = i * kPointsPerItem + k;
        points[order[slot]] = load_point(tile, at);
        if (with_jacobian) {
          const Real* j = tile.jacobians + i * kJacobianComponents * kPointsPerItem + k;
          auto column = [&](std::ptrdiff_t c) {
            return Point(static_cast<double>(j[2 * c * kPointsPerItem]),
                         static_cast<double>(j[(2 * c + 1) * kPointsPerItem]));
          };
          jacobians[order[slot]] = FlowJacobian{column(0), column(1)};
        }
        stats.point_evaluations += static_cast<std::size_t>(tile.evaluations[i]);
        ++stats.points;
      }
    }
  };
  PathlineLauncher<Real>(device, problem, segment, direction, with_jacobian).run(items, fill, take, control, stats);
}

// Work-item (bx, by) holds the pixels x = 16·bx + lane, y = kVectorsPerItem·by + vector; those past the image
// edge repeat the edge pixel and are not written back. Segment `segment`'s inverse flow, then `to_source`.
template <class Real>
std::vector<Point> inverse_grid_with(const kernels_detail::DeviceHandle& device, const WarpProblem& problem,
                                     std::size_t segment, const Similarity& to_source, int width, int height,
                                     const RunControl& control, OpenClRunStats& stats) {
  const auto w = static_cast<std::size_t>(width);
  const auto h = static_cast<std::size_t>(height);
  std::vector<Point> grid = huge_page_vector<Point>(w * h);
  const std::size_t blocks_x = (w + kLanes - 1) / kLanes;
  const std::size_t blocks_y = (h + kVectorsPerItem - 1) / kVectorsPerItem;
  auto pixel = [&](std::size_t item, int k, std::size_t& x, std::size_t& y) {
    x = (item % blocks_x) * kLanes + static_cast<std::size_t>(k % kLanes);
    y = (item / blocks_x) * kVectorsPerItem + static_cast<std::size_t>(k / kLanes);
  };
  auto fill = [&](TileData<Real>& tile) {
    for (std::size_t i = 0; i < tile.count; ++i) {
      for (int k = 0; k < kPointsPerItem; ++k) {
        std::size_t x, y;
        pixel(tile.first + i, k, x, y);
        const std::size_t at = i * kPointsPerItem + k;
        tile.origin_x[at] = static_cast<Real>(static_cast<double>(std::min(x, w - 1)) + 0.5);
        tile.origin_y[at] = static_cast<Real>(static_cast<double>(std::min(y, h - 1)) + 0.5);
        tile.offset_x[at] = Real(0);
        tile.offset_y[at] = Real(0);
      }
    }
  };
  auto take = [&](const TileData<Real>& tile) {
    for (std::size_t i = 0; i < tile.count; ++i) {
      for (int k = 0; k < kPointsPerItem; ++k) {
        std::size_t x, y;
        pixel(tile.first + i, k, x, y);
        if (x >= w || y >= h) continue;
        const std::size_t at = i * kPointsPerItem + k;
        grid[y * w + x] =
            to_source(Point(static_cast<double>(tile.origin_x[at]) + static_cast<double>(tile.offset_x[at]),
                            static_cast<double>(tile.origin_y[at]) + static_cast<double>(tile.offset_y[at])));
        stats.point_evaluations += static_cast<std::size_t>(tile.evaluations[i]);
        ++stats.points;
      }
    }
  };
  PathlineLauncher<Real>(device, problem, segment, Direction::kInverse)
      .run(blocks_x * blocks_y, fill, take, control, stats);
  return grid;
}

// The whole inverse map on a grid: the last segment's inverse flow on the grid kernel; with K > 1 the other
// segments (K−2 … 0) as points, then the pre-alignment's inverse. Progress is split evenly over the segments.
template <class Real>
std::vector<Point> inverse_map_with(const kernels_detail::DeviceHandle& device, const WarpProblem& problem, int width,
                                    int height, const RunControl& control, OpenClRunStats& stats) {
  const std::size_t k = problem.segments().size();
  auto part = [&](std::size_t step) {
    RunControl c = control;
    if (control.progress) {
      c.progress = [&control, step, k](double f) {
        control.progress((static_cast<double>(step) + f) / static_cast<double>(k));
      };
    }
    return c;
  };
  const Similarity to_source = k == 1 ? problem.prealignment().inverse() : Similarity{};
  std::vector<Point> grid = inverse_grid_with<Real>(device, problem, k - 1, to_source, width, height, part(0), stats);
  if (k > 1) {
    for (std::size_t step = 1; step < k; ++step) {
      const std::size_t segment = k - 1 - step;
      if (problem.segments()[segment].field_is_zero) continue;
      flow_points_with<Real>(device, problem, segment, grid, {}, Direction::kInverse, part(step), stats);
    }
    const Similarity inverse = problem.prealignment().inverse();
    for (Point& p : grid) p = inverse(p);
  }
  return grid;
}

// The precision a call runs in. kAuto runs float32 where the tolerance allows it, but where two feature
// trajectories pass very close float32's rounding of the field can keep a step's error estimate above the
// tolerance however short the step (the step collapses) while double integrates the same pathline. On a device
// with cl_khr_fp64 such a call is then run again in double: `attempt(double_precision, control)` runs the call;
// `keep()`, called only when a second attempt may follow, saves what the first overwrites and returns how to put it
// back (null `keep`: nothing to save). Progress never goes back across the two.
template <class Attempt>
void run_in_precision(const kernels_detail::DeviceHandle& device, const WarpProblem& problem, OpenClPrecision precision,
                      const RunControl& control, OpenClRunStats& stats, const Attempt& attempt,
                      const std::function<std::function<void()>()>& keep) {
  stats.double_precision = needs_double(problem, device, precision);
  if (stats.double_precision || precision != OpenClPrecision::kAuto || !device.has_fp64) {
    attempt(stats.double_precision, control);
    return;
  }
  const std::function<void()> restore = keep ? keep() : nullptr;
  RunControl monotonic = control;
  if (control.progress) {
    monotonic.progress = [&control, reported = 0.0](double f) mutable {
      if (f <= reported) return;
      reported = f;
      control.progress(f);
    };
  }
  try {
    attempt(false, monotonic);
  } catch (const NumericalError&) {
    if (restore) restore();
    stats = OpenClRunStats{};
    stats.double_precision = true;
    stats.retried_in_double = true;
    attempt(true, monotonic);
  }
}

}  // namespace

OpenClWarpBackend::OpenClWarpBackend(const OpenClOptions& options)
    : impl_(std::make_unique<Impl>(Impl{kernels_detail::select_device(options), options.precision})) {}

OpenClWarpBackend::~OpenClWarpBackend() = default;

std::string OpenClWarpBackend::device_description() const {
  return impl_->device.device_name + " (" + impl_->device.platform_name + ")";
}

void OpenClWarpBackend::flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                     Direction direction, const RunControl& control) {
  flow(problem, segment, points, {}, direction, control);
}

void OpenClWarpBackend::flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment,
                                                   std::span<Point> points, std::span<FlowJacobian> jacobians,
                                                   Direction direction, const RunControl& control) {
  if (jacobians.size() != points.size()) {
    throw std::invalid_argument("flow_points_with_jacobian: one Jacobian per point");
  }
  for (FlowJacobian& j : jacobians) j = FlowJacobian{};
  flow(problem, segment, points, jacobians, direction, control);
}

// The Jacobian (the variational equation) holds in float32 wherever the positions do: its rounding, about 1e-6
// relative, is far below its truncation error, so both follow the same precision rule.
void OpenClWarpBackend::flow(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                             std::span<FlowJacobian> jacobians, Direction direction, const RunControl& control) {
  const auto start = std::chrono::steady_clock::now();
  OpenClRunStats stats;
  if (!points.empty() && !problem.segments().at(segment).field_is_zero) {
    run_in_precision(
        impl_->device, problem, impl_->precision, control, stats,
        [&](bool double_precision, const RunControl& c) {
          if (double_precision) {
            flow_points_with<double>(impl_->device, problem, segment, points, jacobians, direction, c, stats);
          } else {
            flow_points_with<float>(impl_->device, problem, segment, points, jacobians, direction, c, stats);
          }
        },
        [points, jacobians] {
          // The start points, for a second attempt in double (the first writes its results back tile by tile); the
          // Jacobians start at the identity.
          return [points, jacobians, start = std::vector<Point>(points.begin(), points.end())] {
            std::copy(start.begin(), start.end(), points.begin());
            std::fill(jacobians.begin(), jacobians.end(), FlowJacobian{});
          };
        });
  } else if (control.progress) {
    control.progress(1.0);
  }
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::lock_guard lock(stats_mutex_);
  last_stats_ = stats;
  double_retries_ += stats.retried_in_double ? 1 : 0;
}

std::vector<Point> OpenClWarpBackend::inverse_map_grid(const WarpProblem& problem, int width, int height,
                                                       const RunControl& control) {
  if (width <= 0 || height <= 0) return {};
  if (problem.field_is_zero()) return WarpBackend::inverse_map_grid(problem, width, height, control);
  ensure_growth_scale(*this, problem, Direction::kInverse, control);
  const auto start = std::chrono::steady_clock::now();
  OpenClRunStats stats;
  std::vector<Point> grid;
  run_in_precision(impl_->device, problem, impl_->precision, control, stats,
                   [&](bool double_precision, const RunControl& c) {
                     grid = double_precision ? inverse_map_with<double>(impl_->device, problem, width, height, c, stats)
                                             : inverse_map_with<float>(impl_->device, problem, width, height, c, stats);
                   },
                   {});
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::lock_guard lock(stats_mutex_);
  last_stats_ = stats;
  double_retries_ += stats.retried_in_double ? 1 : 0;
  return grid;
}

std::uint64_t OpenClWarpBackend::double_retries() const {
  std::lock_guard lock(stats_mutex_);
  return double_retries_;
}

OpenClRunStats OpenClWarpBackend::last_run_stats() const {
  std::lock_guard lock(stats_mutex_);
  return last_stats_;
}

}  // namespace texwarp
