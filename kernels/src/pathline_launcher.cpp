// Tiled launches of the pathline kernel: see pathline_launcher.hpp.
#include "pathline_launcher.hpp"

#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "double_buffer.hpp"
#include "opencl_calls.hpp"
#include "packed_field.hpp"
#include "pathline_kernel_args.hpp"
#include "pathline_program.hpp"
#include "pathline_status.hpp"
#include "texwarp/core/numerical_error.hpp"
#include "tile_plan.hpp"

namespace texwarp::kernels_detail {
namespace {

// The arguments that hold for every tile of a run: the packed field, the time span and tolerance, the scratch.
template <class Real>
PathlineKernelArgs<Real> run_arguments(const cl::Context& context, const PackedField<Real>& field, const TilePlan& plan,
                                       Direction direction, double tolerance_px) {
  PathlineKernelArgs<Real> a;
  const bool forward = direction == Direction::kForward;
  a.template get<"n">() = field.positional;
  a.template get<"m">() = field.gradient;
  a.template get<"pairs16">() = field.pairs16;
  a.template get<"pow_mode">() = static_cast<cl_int>(field.pow_mode);
  a.template get<"half_alpha">() = field.half_alpha;
  a.template get<"log_inv_length2">() = field.log_inv_length2;
  a.template get<"feat">() = read_only_buffer<Real>(context, field.positional_records);
  a.template get<"grad">() = read_only_buffer<Real>(context, field.gradient_records);
  a.template get<"pairs">() = read_only_buffer<Real>(context, field.pair_records);
  a.template get<"t_start">() = forward ? Real(0) : Real(1);
  a.template get<"t_end">() = forward ? Real(1) : Real(0);
  a.template get<"local_tol">() = static_cast<Real>(kLocalErrorFraction * tolerance_px);
  a.template get<"first_step">() = field.first_step;
  a.template get<"scratch">() = cl::Buffer(context, CL_MEM_READ_WRITE, plan.items_per_tile * plan.scratch.item_bytes);
  a.template get<"scratch_stride">() = static_cast<cl_int>(plan.scratch.stride);
  a.template get<"z_offset">() = static_cast<cl_int>(plan.scratch.z_offset);
  a.template get<"acc_offset">() = static_cast<cl_int>(plan.scratch.acc_offset);
  a.template get<"events">() = field.events;
  a.template get<"event_records">() = read_only_buffer<Real>(context, field.event_records);
  return a;
}

// One tile in flight: the per-tile device buffers and their host copies.
template <class Real>
class TileSlot {
 public:
  TileSlot(const cl::Context& context, std::size_t items, bool jacobian)
      : points_(items * kPointsPerItem),
        origin_x_(context, CL_MEM_READ_ONLY, points_ * sizeof(Real)),
        origin_y_(context, CL_MEM_READ_ONLY, points_ * sizeof(Real)),
        offset_x_(context, CL_MEM_READ_WRITE, points_ * sizeof(Real)),
        offset_y_(context, CL_MEM_READ_WRITE, points_ * sizeof(Real)),
        status_(context, CL_MEM_WRITE_ONLY, kStatusStride * items * sizeof(cl_int)),
        ox_(points_),
        oy_(points_),
        px_(points_),
        py_(points_),
        words_(kStatusStride * items),
        evaluations_(items) {
    if (jacobian) {
      jacobian_ = cl::Buffer(context, CL_MEM_WRITE_ONLY, kJacobianComponents * points_ * sizeof(Real));
      jac_.resize(kJacobianComponents * points_);
    }
  }

  // Fills the tile's points, writes them, launches the kernel on them and reads the results back (all queued).
  void submit(const cl::CommandQueue& queue, cl::Kernel& kernel, PathlineKernelArgs<Real>& args, Tile tile,
              const typename PathlineLauncher<Real>::Fill& fill) {
    TileData<Real> data = view(tile);
    fill(data);
    const std::size_t n = tile.count * kPointsPerItem;
    enqueue_write(queue, origin_x_, std::span<const Real>(ox_.data(), n));
    enqueue_write(queue, origin_y_, std::span<const Real>(oy_.data(), n));
    enqueue_write(queue, offset_x_, std::span<const Real>(px_.data(), n));
    enqueue_write(queue, offset_y_, std::span<const Real>(py_.data(), n));
    args.template set<"org_x">(kernel, origin_x_);
    args.template set<"org_y">(kernel, origin_y_);
    args.template set<"off_x">(kernel, offset_x_);
    args.template set<"off_y">(kernel, offset_y_);
    args.template set<"status">(kernel, status_);
    args.template set<"jacobian">(kernel, jacobian_);
    queue.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(tile.count), cl::NDRange(1));
    enqueue_read(queue, offset_x_, std::span<Real>(px_.data(), n));
    enqueue_read(queue, offset_y_, std::span<Real>(py_.data(), n));
    if (!jac_.empty()) enqueue_read(queue, jacobian_, std::span<Real>(jac_.data(), kJacobianComponents * n));
    enqueue_read(queue, status_, std::span<std::int32_t>(words_.data(), kStatusStride * tile.count), &done_);
    queue.flush();
  }

  // Waits for the tile, decodes its status (NumericalError on a failed point) and hands its results to take.
  void complete(Tile tile, const typename PathlineLauncher<Real>::Take& take) {
    done_.wait();
    const TileData<Real> data = view(tile);
    decode_status(words_, std::span<int>(evaluations_.data(), tile.count), [&](std::size_t item) {
      const std::size_t k = item * kPointsPerItem;  // the item's first point, where the failure stopped it
      return Point(static_cast<double>(ox_[k]) + static_cast<double>(px_[k]),
                   static_cast<double>(oy_[k]) + static_cast<double>(py_[k]));
    });
    take(data);
  }

 private:
  TileData<Real> view(Tile tile) {
    return {tile.first, tile.count, ox_.data(),          oy_.data(),
            px_.data(), py_.data(), evaluations_.data(), jac_.empty() ? nullptr : jac_.data()};
  }

  std::size_t points_;
  cl::Buffer origin_x_, origin_y_, offset_x_, offset_y_, status_, jacobian_;
  std::vector<Real> ox_, oy_, px_, py_, jac_;
  std::vector<std::int32_t> words_;
  std::vector<int> evaluations_;
  cl::Event done_;
};

}  // namespace

template <class Real>
PathlineLauncher<Real>::PathlineLauncher(const DeviceHandle& device, const WarpProblem& problem, std::size_t segment,
                                         Direction direction, bool with_jacobian)
    : device_(device), problem_(problem), segment_(segment), direction_(direction), with_jacobian_(with_jacobian) {}

template <class Real>
void PathlineLauncher<Real>::run(std::size_t items, const Fill& fill, const Take& take, const RunControl& control,
                                 OpenClRunStats& stats) const {
  constexpr bool kDouble = std::is_same_v<Real, double>;
  const PackedField<Real> field = pack_field<Real>(problem_, segment_);
  const TilePlan plan = plan_tiles({items, static_cast<std::size_t>(field.positional),
                                    static_cast<std::size_t>(field.gradient), static_cast<std::size_t>(field.pairs16),
                                    with_jacobian_, kDouble, device_.compute_units, device_.max_alloc_bytes});
  const cl::Program program = pathline_program(device_, {kDouble, with_jacobian_});
  with_cl_errors("OpenCL pathline run on " + device_.device_name + " failed", [&] {
    cl::CommandQueue queue(device_.context, device_.device);
    cl::Kernel kernel(program, kPathlineKernelName.data());
    PathlineKernelArgs<Real> args =
        run_arguments(device_.context, field, plan, direction_, problem_.pathline_tolerance_px(direction_));
    args.bind(kernel);
    DoubleBuffer<TileSlot<Real>> slots(device_.context, plan.items_per_tile, with_jacobian_);
    const QueueDrain drain(queue);  // before the slots' host memory goes
    slots.run(
        plan.tiles,
        [&] {
          if (control.canceled()) throw CanceledError();
        },
        [&](TileSlot<Real>& slot, Tile tile) {
          slot.submit(queue, kernel, args, tile, fill);
          ++stats.launches;
        },
        [&](TileSlot<Real>& slot, Tile tile) {
          slot.complete(tile, take);
          if (control.progress)
            control.progress(static_cast<double>(tile.first + tile.count) / static_cast<double>(items));
        });
  });
}

template class PathlineLauncher<float>;
template class PathlineLauncher<double>;

}  // namespace texwarp::kernels_detail
