// PackedField: one segment of a WarpProblem's trajectories in the flat records the kernels read
// (kernels/cl/velocity_field.cl): positions split into hi + lo parts of the kernel's real type, pair differences for
// c_ij(t), the α mode.
#pragma once

#include <cstddef>
#include <vector>

#include "kernel_contract.hpp"
#include "texwarp/core/dormand_prince.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp::kernels_detail {

template <class Real>
struct PackedField {
  int positional = 0;  // n
  int gradient = 0;    // m
  int pairs16 = 0;     // n(n−1)/2 rounded up to a multiple of 16
  PowMode pow_mode = PowMode::kGeneral;
  Real half_alpha = 0;       // α/2
  Real log_inv_length2 = 0;  // ln(1 / L²), L = TrajectorySegment::weight_length_px
  // The record layouts of kernel_contract.hpp; every vector holds at least one record (zeros), so that no device
  // buffer is empty.
  std::vector<Real> positional_records;  // n records of kPositionalStride: F_hi, F_lo, D
  std::vector<Real> gradient_records;    // m records of kGradientStride: F_hi, F_lo, D, κ
  std::vector<Real> pair_records;        // kPairArrays arrays of pairs16 (padding pairs: ΔF = 1, ΔD = 0)
  int events = 0;                        // near-collisions that cap the step size (see pathline.cl)
  std::vector<Real> event_records;       // kEventStride per event: t*, width
  // The segment's first step (dormand_prince::first_step).
  Real first_step = dormand_prince::kMinFirstStep;
};

// The segment's near-collisions (TrajectorySegment::near_collisions) become (t*, width) records, the kMaxEvents
// narrowest at most: every step of every work-item scans them.
inline constexpr std::size_t kMaxEvents = 64;

template <class Real>
PackedField<Real> pack_field(const WarpProblem& problem, std::size_t segment);

// The larger-than-float part of x, as Real, and what is left: hi + lo == x to about 2^−48 relative for floats.
template <class Real>
inline void split(double x, Real& hi, Real& lo) {
  hi = static_cast<Real>(x);
  lo = static_cast<Real>(x - static_cast<double>(hi));
}

extern template PackedField<float> pack_field<float>(const WarpProblem&, std::size_t);
extern template PackedField<double> pack_field<double>(const WarpProblem&, std::size_t);

}  // namespace texwarp::kernels_detail
