// Flow growth: an error made in one trajectory segment grows through the segments integrated after it (their
// Jacobians stretch it), and the planned sets' segments multiply their growths: the permuted grid with gradient
// features, 4 segments each stretching by 2–3, missed 0.05 px by 1.3× at every pixel (against 1e-9 px). For K > 1
// segments a map's pathlines are integrated tighter by the growth scale, measured once per problem and direction
// on a probe grid by the map's own backend before its first pathline: the integration's own budget
// (kLocalErrorFraction, a tenth of the tolerance, room for a growth of 10 within a segment) then holds the growths of
// the whole chain.
#pragma once

#include <array>
#include <atomic>
#include <mutex>
#include <vector>

#include "texwarp/core/direction.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/run_control.hpp"

namespace texwarp {

class WarpBackend;
class WarpProblem;

// The probe: kGrowthProbeSide² points over the features' box in flow space (where the direction's pathlines start),
// widened by kGrowthProbeMargin of its size on each side.
inline constexpr int kGrowthProbeSide = 32;
inline constexpr double kGrowthProbeMargin = 0.25;
// The scale never goes below this (a growth beyond 1 / kMinGrowthScale is integrated as if it were that: about 4× the
// steps at most).
inline constexpr double kMinGrowthScale = 1e-3;

// Shared by a problem and its copies (WarpProblem::with_tolerance): the same segments grow the same.
struct FlowGrowthCache {
  std::array<std::atomic<double>, 2> scale{1.0, 1.0};  // by Direction; 1 until measured
  std::array<std::once_flag, 2> measured;
};

// The growth of a chain of segments at one point, Σ_m Π_{r=m..K} σ_r (σ_m the largest singular value of segment
// m's Jacobian along the point's pathline, taken as at least 1: segment m's error grown within itself and through
// every segment after it), one segment at a time in integration order: from 0, each σ turns g into (g + 1)·σ.
inline double chain_growth_step(double growth, double sigma) { return (growth + 1.0) * (sigma > 1.0 ? sigma : 1.0); }

// The probe: kGrowthProbeSide² points in flow space, row by row.
std::vector<Point> growth_probe_points(const WarpProblem& problem, Direction direction);

// min(1, (1 / kLocalErrorFraction) / max over the probe of chain_growth), at least kMinGrowthScale; 1 for K = 1.
// Runs the probe's pathlines with their Jacobians on `backend`, segment by segment (control's cancel and threads;
// no progress).
double measure_growth_scale(WarpBackend& backend, const WarpProblem& problem, Direction direction,
                            const RunControl& control);

// Measures the problem's growth scale for `direction` once (thread-safe; copies of the problem share it), before the
// first pathline of a map with K > 1 segments: WarpBackend::flow_points and the backends' grid maps call it.
void ensure_growth_scale(WarpBackend& backend, const WarpProblem& problem, Direction direction,
                         const RunControl& control);

}  // namespace texwarp
