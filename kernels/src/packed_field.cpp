// Packing of a WarpProblem's trajectories for the kernels: see packed_field.hpp.
#include "packed_field.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace texwarp::kernels_detail {
namespace {

// TW_POW_* of velocity_field.cl: q^(α/2) without log/exp for the common α.
int pow_mode_for(double alpha) {
  if (alpha == 2.0) return 1;
  if (alpha == 3.0) return 2;
  if (alpha == 1.5) return 3;
  if (alpha == 1.0) return 4;
  if (alpha == 4.0) return 5;
  return 0;
}

}  // namespace

template <class Real>
PackedField<Real> pack_field(const WarpProblem& problem) {
  const auto& pos = problem.positional();
  const auto& grad = problem.gradient();
  PackedField<Real> f;
  f.positional = static_cast<int>(pos.size());
  f.gradient = static_cast<int>(grad.size());
  const std::size_t n = pos.size();
  const std::size_t pairs = n < 2 ? 0 : n * (n - 1) / 2;
  const std::size_t pairs16 = (pairs + kLanes - 1) / kLanes * kLanes;
  f.pairs16 = static_cast<int>(pairs16);
  f.pow_mode = pow_mode_for(problem.alpha());
  f.half_alpha = static_cast<Real>(0.5 * problem.alpha());
  f.log_inv_length2 = static_cast<Real>(-2.0 * std::log(problem.weight_length_px()));

  f.positional_records.resize(n * kPositionalStride);
  for (std::size_t i = 0; i < n; ++i) {
    Real* r = f.positional_records.data() + i * kPositionalStride;
    split(pos[i].start.real(), r[0], r[2]);
    split(pos[i].start.imag(), r[1], r[3]);
    r[4] = static_cast<Real>(pos[i].velocity.real());
    r[5] = static_cast<Real>(pos[i].velocity.imag());
  }
  f.gradient_records.assign(std::max<std::size_t>(1, grad.size()) * kGradientStride, Real(0));
  for (std::size_t g = 0; g < grad.size(); ++g) {
    Real* r = f.gradient_records.data() + g * kGradientStride;
    split(grad[g].start.real(), r[0], r[2]);
    split(grad[g].start.imag(), r[1], r[3]);
    r[4] = static_cast<Real>(grad[g].velocity.real());
    r[5] = static_cast<Real>(grad[g].velocity.imag());
    r[6] = static_cast<Real>(grad[g].rate.real());
    r[7] = static_cast<Real>(grad[g].rate.imag());
  }
  // At least one vector of pairs so that the buffer is never empty (the kernel strides by pairs16, which is 0
  // then); padding pairs have c = 0.
  const std::size_t stored = std::max<std::size_t>(pairs16, kLanes);
  f.pair_records.assign(4 * stored, Real(0));
  Real* f0x = f.pair_records.data();
  Real* f0y = f0x + stored;
  Real* ddx = f0y + stored;
  Real* ddy = ddx + stored;
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

  // Near-collision events, the narrowest first.
  std::vector<NearCollision> events = problem.near_collisions();
  std::sort(events.begin(), events.end(),
            [](const NearCollision& x, const NearCollision& y) { return x.width < y.width; });
  if (events.size() > kMaxEvents) events.resize(kMaxEvents);
  f.events = static_cast<int>(events.size());
  f.event_records.assign(2 * std::max<std::size_t>(1, events.size()), Real(0));
  for (std::size_t e = 0; e < events.size(); ++e) {
    f.event_records[2 * e] = static_cast<Real>(events[e].t);
    f.event_records[2 * e + 1] = static_cast<Real>(events[e].width);
  }
  return f;
}

template PackedField<float> pack_field<float>(const WarpProblem&);
template PackedField<double> pack_field<double>(const WarpProblem&);

}  // namespace texwarp::kernels_detail
