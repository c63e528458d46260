// The Dormand–Prince 5(4) tableau and step controller: one source for the CPU reference integrator
// (core/src/pathline.cpp) and the OpenCL kernel, whose copy kernels/src/kernel_contract.hpp emits from these values.
#pragma once

#include <array>

namespace texwarp::dormand_prince {

// Dormand & Prince (1980); stage 7 is evaluated at the 5th-order solution (FSAL).
inline constexpr int kStages = 7;
inline constexpr std::array<double, kStages> kC = {0.0, 1.0 / 5, 3.0 / 10, 4.0 / 5, 8.0 / 9, 1.0, 1.0};
inline constexpr double kA[kStages][kStages - 1] = {
    {},
    {1.0 / 5},
    {3.0 / 40, 9.0 / 40},
    {44.0 / 45, -56.0 / 15, 32.0 / 9},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656},
    {35.0 / 384, 0.0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84},
};
// 5th-order weights minus the embedded 4th-order ones: the local error estimate.
inline constexpr std::array<double, kStages> kE = {71.0 / 57600,      0.0,        -71.0 / 16695, 71.0 / 1920,
                                                   -17253.0 / 339200, 22.0 / 525, -1.0 / 40};

// Step controller: the first step (in t, kMinFirstStep or the whole segment, see first_step), the smallest before the
// integration gives up (double precision), and the factor new step / old step =
// clamp(kSafety·(allowed / err)^(1/4), kMaxShrink, kMaxGrowth).
inline constexpr double kMinFirstStep = 0.125;
inline constexpr double kWholeSegmentTimeScale = 4.0;
inline constexpr double kMinStep = 1e-12;
inline constexpr double kSafety = 0.9;
inline constexpr double kMaxGrowth = 5.0;
inline constexpr double kMaxShrink = 0.2;

// The first step of a segment whose field changes within time_scale at the fastest (TrajectorySegment::time_scale):
// the whole segment where no two features close their distance within kWholeSegmentTimeScale segments (features that
// move with their neighbours, time scales 5–7 on a flattening's smooth sets), kMinFirstStep otherwise. A smooth field
// is then one step (7 evaluations) where its error estimate allows; from a first step of 1/8 growing at most 5× a
// step it took three (19). Shorter time scales keep 1/8: a longer first step there can have its stages miss where the
// field changes, and its error estimate with them (whole-segment first steps on crossing trajectories: errors up to
// 2.3× the tolerance; a quarter of the time scale: the gradient set at 2.9× where 1/8 gives 1.8×).
inline double first_step(double time_scale) { return time_scale >= kWholeSegmentTimeScale ? 1.0 : kMinFirstStep; }

}  // namespace texwarp::dormand_prince
