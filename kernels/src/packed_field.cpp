// Packing of a WarpProblem's trajectories for the kernels: see packed_field.hpp.
#include "packed_field.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace texwarp::kernels_detail {
namespace {

// q^(α/2) without log/exp for the common α.
PowMode pow_mode_for(double alpha) {
  if (alpha == 2.0) return PowMode::kAlpha2;
  if (alpha == 3.0) return PowMode::kAlpha3;
  if (alpha == 1.5) return PowMode::kAlpha3Halves;
  if (alpha == 1.0) return PowMode::kAlpha1;
  if (alpha == 4.0) return PowMode::kAlpha4;
  return PowMode::kGeneral;
}

// A feature's position and velocity into its record.
template <class Real>
void store_trajectory(Real* r, Point start, Point velocity) {
  split(start.real(), r[kRecordHiX], r[kRecordLoX]);
  split(start.imag(), r[kRecordHiY], r[kRecordLoY]);
  r[kRecordVelocityX] = static_cast<Real>(velocity.real());
  r[kRecordVelocityY] = static_cast<Real>(velocity.imag());
}

}  // namespace

template <class Real>
PackedField<Real> pack_field(const WarpProblem& problem, std::size_t segment) {
  const TrajectorySegment& seg = problem.segments().at(segment);
  const auto& pos = seg.positional;
  const auto& grad = seg.gradient;
  PackedField<Real> f;
  f.positional = static_cast<int>(pos.size());
  f.gradient = static_cast<int>(grad.size());
  const std::size_t n = pos.size();
  const std::size_t pairs = n < 2 ? 0 : n * (n - 1) / 2;
  const std::size_t pairs16 = (pairs + kLanes - 1) / kLanes * kLanes;
  f.pairs16 = static_cast<int>(pairs16);
  f.pow_mode = pow_mode_for(problem.alpha());
  f.half_alpha = static_cast<Real>(0.5 * problem.alpha());
  f.log_inv_length2 = static_cast<Real>(-2.0 * std::log(seg.weight_length_px));

  f.positional_records.assign(std::max<std::size_t>(1, n) * kPositionalStride, Real(0));
  for (std::size_t i = 0; i < n; ++i) {
    store_trajectory(f.positional_records.data() + i * kPositionalStride, pos[i].start, pos[i].velocity);
  }
  f.gradient_records.assign(std::max<std::size_t>(1, grad.size()) * kGradientStride, Real(0));
  for (std::size_t g = 0; g < grad.size(); ++g) {
    Real* r = f.gradient_records.data() + g * kGradientStride;
    store_trajectory(r, grad[g].start, grad[g].velocity);
    r[kRecordRateX] = static_cast<Real>(grad[g].rate.real());
    r[kRecordRateY] = static_cast<Real>(grad[g].rate.imag());
  }
  // At least one vector of pairs so that the buffer is never empty (the kernel strides by pairs16, which is 0
  // then); padding pairs have c = 0.
  const std::size_t stored = std::max<std::size_t>(pairs16, kLanes);
  f.pair_records.assign(kPairArrays * stored, Real(0));
  Real* f0x = f.pair_records.data() + kPairStartX * stored;
  Real* f0y = f.pair_records.data() + kPairStartY * stored;
  Real* ddx = f.pair_records.data() + kPairVelocityX * stored;
  Real* ddy = f.pair_records.data() + kPairVelocityY * stored;
  std::fill(f0x, f0x + stored, Real(1));
  std::size_t idx = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j, ++idx) {
      const Point df = pos[j].start - pos[i].start;
      const Point dd = pos[j].velocity - pos[i].velocity;
      f0x[idx] = static_cast<Real>(df.real());
      f0y[idx] = static_cast<Real>(df.imag());
      ddx[idx] = static_cast<Real>(dd.real());
      ddy[idx] = static_cast<Real>(dd.imag());
    }
  }

  f.first_step = static_cast<Real>(dormand_prince::first_step(seg.time_scale));
  // Near-collision events, the narrowest first.
  std::vector<NearCollision> events = seg.near_collisions;
  std::sort(events.begin(), events.end(),
            [](const NearCollision& x, const NearCollision& y) { return x.width < y.width; });
  if (events.size() > kMaxEvents) events.resize(kMaxEvents);
  f.events = static_cast<int>(events.size());
  f.event_records.assign(kEventStride * std::max<std::size_t>(1, events.size()), Real(0));
  for (std::size_t e = 0; e < events.size(); ++e) {
    f.event_records[kEventStride * e + kEventTime] = static_cast<Real>(events[e].t);
    f.event_records[kEventStride * e + kEventWidth] = static_cast<Real>(events[e].width);
  }
  return f;
}

template PackedField<float> pack_field<float>(const WarpProblem&, std::size_t);
template PackedField<double> pack_field<double>(const WarpProblem&, std::size_t);

}  // namespace texwarp::kernels_detail
