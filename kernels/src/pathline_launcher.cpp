// Tiled launches of the pathline kernel: see pathline_launcher.hpp.
#include "pathline_launcher.hpp"

#include <algorithm>
#include <cstdio>
#include <string>
#include <type_traits>
#include <vector>

#include "packed_field.hpp"
#include "texwarp/core/numerical_error.hpp"
#include "texwarp/kernels/opencl_error.hpp"

namespace texwarp::kernels_detail {
namespace {

// Launch sizing: about this many arithmetic operations per tile (≈ 0.1–0.3 s on a 2-core AVX-512 CPU), at most
// this much scratch, and at least this many work-items per compute unit (load balance).
constexpr double kOpsPerTile = 3e10;
constexpr double kEvaluationsGuess = 100.0;  // field evaluations per point, for the estimate only
constexpr std::size_t kScratchBudgetBytes = std::size_t{96} << 20;
constexpr std::size_t kMinItemsPerComputeUnit = 4;
constexpr std::size_t kColumnBlock = 128;               // TW_COLUMN_BLOCK
constexpr std::size_t kGradientColumnBlockFloat = 40;   // TW_GRADIENT_COLUMN_BLOCK
constexpr std::size_t kGradientColumnBlockDouble = 20;  // TW_GRADIENT_COLUMN_BLOCK with TW_DOUBLE
constexpr std::size_t kGradientRecord = 4;              // TW_GRADIENT_RECORD / TW_VECS (z, z·h.x, z·h.y), factor f
constexpr std::size_t kGradientRowSums = 6;             // R_i, Q_i^x, Q_i^y (complex) per row in acc
constexpr double kGradientPairCost = 3.0;               // per-point field work with ∇v, relative to v alone

// TW_STATUS_* of pathline.cl.
constexpr int kStatusNonFinite = 1;
constexpr int kStatusStepCollapse = 2;

std::size_t round_up(std::size_t x, std::size_t m) { return (x + m - 1) / m * m; }

template <class Real>
cl::Buffer read_only_buffer(const cl::Context& context, const std::vector<Real>& data) {
  return cl::Buffer(context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, data.size() * sizeof(Real),
                    const_cast<Real*>(data.data()));
}

std::string describe_failure(int code, double x, double y) {
  char where[96];
  std::snprintf(where, sizeof where, "(%.6g, %.6g)", x, y);
  if (code == kStatusNonFinite) {
    return std::string("pathline integration on the OpenCL device produced a non-finite value for a point near ") +
           where;
  }
  if (code == kStatusStepCollapse) {
    return std::string("pathline step size collapsed on the OpenCL device for a point near ") + where +
           " (the field is not smooth enough there; are two features nearly colliding?)";
  }
  return std::string("pathline integration on the OpenCL device did not finish for a point near ") + where;
}

}  // namespace

template <class Real>
PathlineLauncher<Real>::PathlineLauncher(const DeviceHandle& device, const WarpProblem& problem, Direction direction,
                                         bool with_jacobian)
    : device_(device), problem_(problem), direction_(direction), with_jacobian_(with_jacobian) {}

template <class Real>
void PathlineLauncher<Real>::run(std::size_t items, const Fill& fill, const Take& take, const RunControl& control,
                                 OpenClRunStats& stats) const {
  constexpr bool kDouble = std::is_same_v<Real, double>;
  const PackedField<Real> f = pack_field<Real>(problem_);
  const std::size_t n = static_cast<std::size_t>(f.positional);
  const std::size_t m = static_cast<std::size_t>(f.gradient);

  // Scratch per work-item: cx, cy (pairs16 each), F_lo + t·D of positional and gradient features, z (n·64),
  // and the partial row sums of the column-blocked pair loop (n·128, when n > its block of 128 columns); with
  // the Jacobian, column records of z, z·h and the factors f (4·n·64) and six row sums (n·384, when n exceeds
  // its block).
  const std::size_t record = with_jacobian_ ? kGradientRecord : 1;
  const std::size_t row_sums = with_jacobian_ ? kGradientRowSums : 2;
  const std::size_t block =
      with_jacobian_ ? (kDouble ? kGradientColumnBlockDouble : kGradientColumnBlockFloat) : kColumnBlock;
  const std::size_t z_offset = round_up(2 * static_cast<std::size_t>(f.pairs16) + 2 * n + 2 * m, kLanes);
  const std::size_t acc_offset = z_offset + record * n * kPointsPerItem;
  const std::size_t acc_size = n > block ? row_sums * n * kPointsPerItem : 0;
  const std::size_t stride = std::max<std::size_t>(acc_offset + acc_size, kLanes);
  const std::size_t item_bytes = stride * sizeof(Real);

  const double pair_cost = with_jacobian_ ? kGradientPairCost : 1.0;
  const double ops_per_item = kPointsPerItem * kEvaluationsGuess *
                              (pair_cost * (static_cast<double>(n) * static_cast<double>(n) +
                                            30.0 * static_cast<double>(n + m)) +
                               60.0);
  const std::size_t by_time = std::max<std::size_t>(1, static_cast<std::size_t>(kOpsPerTile / ops_per_item));
  const std::size_t memory = std::min(kScratchBudgetBytes, device_.max_alloc_bytes);
  const std::size_t by_memory = std::max<std::size_t>(1, memory / item_bytes);
  const std::size_t min_items = kMinItemsPerComputeUnit * device_.compute_units;
  const std::size_t per_tile = std::min({items, by_memory, std::max(by_time, min_items)});
  const std::size_t points_per_tile = per_tile * kPointsPerItem;

  const std::string options = std::string("-DTW_VECS=") + std::to_string(kVectorsPerItem) +
                              (kDouble ? " -DTW_DOUBLE" : "") +
                              (with_jacobian_ ? " -DTW_JACOBIAN -DTW_JACOBIAN_ERROR_LENGTH=((real)" +
                                                    std::to_string(kJacobianErrorLengthPx) + ")"
                                              : "");
  const cl::Program program = pathline_program(device_, options);

  try {
    const cl::Context& context = device_.context;
    cl::CommandQueue queue(context, device_.device);
    cl::Kernel kernel(program, "flow_pathlines");

    const cl::Buffer positional = read_only_buffer(context, f.positional_records.empty()
                                                                ? std::vector<Real>(kLanes, Real(0))
                                                                : f.positional_records);
    const cl::Buffer gradient = read_only_buffer(context, f.gradient_records);
    const cl::Buffer pairs = read_only_buffer(context, f.pair_records);
    const cl::Buffer events = read_only_buffer(context, f.event_records);
    const std::size_t point_bytes = points_per_tile * sizeof(Real);
    cl::Buffer scratch(context, CL_MEM_READ_WRITE, per_tile * item_bytes);

    const bool forward = direction_ == Direction::kForward;
    const Real t_start = forward ? Real(0) : Real(1);
    const Real t_end = forward ? Real(1) : Real(0);
    const Real local_tol = static_cast<Real>(kLocalErrorFraction * problem_.tolerance_px());
    kernel.setArg(0, static_cast<cl_int>(n));
    kernel.setArg(1, static_cast<cl_int>(m));
    kernel.setArg(2, static_cast<cl_int>(f.pairs16));
    kernel.setArg(3, static_cast<cl_int>(f.pow_mode));
    kernel.setArg(4, f.half_alpha);
    kernel.setArg(5, f.log_inv_length2);
    kernel.setArg(6, positional);
    kernel.setArg(7, gradient);
    kernel.setArg(8, pairs);
    kernel.setArg(9, t_start);
    kernel.setArg(10, t_end);
    kernel.setArg(11, local_tol);
    kernel.setArg(16, scratch);
    kernel.setArg(17, static_cast<cl_int>(stride));
    kernel.setArg(18, static_cast<cl_int>(z_offset));
    kernel.setArg(19, static_cast<cl_int>(acc_offset));
    kernel.setArg(20, static_cast<cl_int>(f.events));
    kernel.setArg(21, events);

    // Two tiles in flight: while the device integrates one, the host fills the next and takes the previous
    // one's results. The in-order queue runs the kernels one after the other, so they share the scratch.
    struct Slot {
      cl::Buffer origin_x, origin_y, offset_x, offset_y, status, jacobian;
      std::vector<Real> ox, oy, px, py, jac;
      std::vector<cl_int> codes;
      std::vector<int> evaluations;
      cl::Event done;
      std::size_t first = 0;
      std::size_t count = 0;
    };
    Slot slots[2];
    for (Slot& slot : slots) {
      slot.origin_x = cl::Buffer(context, CL_MEM_READ_ONLY, point_bytes);
      slot.origin_y = cl::Buffer(context, CL_MEM_READ_ONLY, point_bytes);
      slot.offset_x = cl::Buffer(context, CL_MEM_READ_WRITE, point_bytes);
      slot.offset_y = cl::Buffer(context, CL_MEM_READ_WRITE, point_bytes);
      slot.status = cl::Buffer(context, CL_MEM_WRITE_ONLY, 2 * per_tile * sizeof(cl_int));
      if (with_jacobian_) {
        slot.jacobian = cl::Buffer(context, CL_MEM_WRITE_ONLY, 4 * point_bytes);
        slot.jac.resize(4 * points_per_tile);
      }
      slot.ox.resize(points_per_tile);
      slot.oy.resize(points_per_tile);
      slot.px.resize(points_per_tile);
      slot.py.resize(points_per_tile);
      slot.codes.resize(2 * per_tile);
      slot.evaluations.resize(per_tile);
    }
    // Whatever ends the run (results, an exception), nothing may still write into the slots' host memory.
    struct Drain {
      cl::CommandQueue& queue;
      ~Drain() {
        try {
          queue.finish();
        } catch (const cl::Error&) {
        }
      }
    } drain{queue};

    auto submit = [&](Slot& slot, std::size_t first) {
      slot.first = first;
      slot.count = std::min(per_tile, items - first);
      const std::size_t bytes = slot.count * kPointsPerItem * sizeof(Real);
      TileData<Real> tile{first,          slot.count,     slot.ox.data(), slot.oy.data(),
                          slot.px.data(), slot.py.data(), nullptr,        nullptr};
      fill(tile);
      queue.enqueueWriteBuffer(slot.origin_x, CL_FALSE, 0, bytes, slot.ox.data());
      queue.enqueueWriteBuffer(slot.origin_y, CL_FALSE, 0, bytes, slot.oy.data());
      queue.enqueueWriteBuffer(slot.offset_x, CL_FALSE, 0, bytes, slot.px.data());
      queue.enqueueWriteBuffer(slot.offset_y, CL_FALSE, 0, bytes, slot.py.data());
      kernel.setArg(12, slot.origin_x);
      kernel.setArg(13, slot.origin_y);
      kernel.setArg(14, slot.offset_x);
      kernel.setArg(15, slot.offset_y);
      kernel.setArg(22, slot.status);
      if (with_jacobian_) kernel.setArg(23, slot.jacobian);
      queue.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(slot.count), cl::NDRange(1));
      queue.enqueueReadBuffer(slot.offset_x, CL_FALSE, 0, bytes, slot.px.data());
      queue.enqueueReadBuffer(slot.offset_y, CL_FALSE, 0, bytes, slot.py.data());
      if (with_jacobian_) queue.enqueueReadBuffer(slot.jacobian, CL_FALSE, 0, 4 * bytes, slot.jac.data());
      queue.enqueueReadBuffer(slot.status, CL_FALSE, 0, 2 * slot.count * sizeof(cl_int), slot.codes.data(), nullptr,
                              &slot.done);
      queue.flush();
      ++stats.launches;
    };
    auto complete = [&](Slot& slot) {
      slot.done.wait();
      for (std::size_t i = 0; i < slot.count; ++i) {
        if (slot.codes[2 * i] != 0) {
          const std::size_t k = i * kPointsPerItem;
          throw NumericalError(describe_failure(slot.codes[2 * i],
                                                static_cast<double>(slot.ox[k]) + static_cast<double>(slot.px[k]),
                                                static_cast<double>(slot.oy[k]) + static_cast<double>(slot.py[k])));
        }
        slot.evaluations[i] = slot.codes[2 * i + 1];
      }
      const TileData<Real> tile{slot.first, slot.count, slot.ox.data(), slot.oy.data(), slot.px.data(),
                                slot.py.data(), slot.evaluations.data(), with_jacobian_ ? slot.jac.data() : nullptr};
      take(tile);
      if (control.progress) {
        control.progress(static_cast<double>(slot.first + slot.count) / static_cast<double>(items));
      }
    };

    if (control.canceled()) throw CanceledError();
    submit(slots[0], 0);
    std::size_t next = per_tile;
    for (int current = 0;; current = 1 - current) {
      if (control.canceled()) throw CanceledError();
      const bool more = next < items;
      if (more) {
        submit(slots[1 - current], next);
        next += per_tile;
      }
      complete(slots[current]);
      if (!more) break;
    }
  } catch (const cl::Error& e) {
    throw OpenClError("OpenCL pathline run on " + device_.device_name + " failed: " + describe_cl_error(e));
  }
}

template class PathlineLauncher<float>;
template class PathlineLauncher<double>;

}  // namespace texwarp::kernels_detail
