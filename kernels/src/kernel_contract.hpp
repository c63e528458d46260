// The host ↔ kernel contract of the pathline program, stated once: every constant, status code, mode and record
// layout that both the C++ host and kernels/cl/*.cl use, and the Dormand–Prince tableau (from core). The table
// kKernelConstants emits the kernel's #define prelude (kernel_prelude.hpp); the .cl files use only the names.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string_view>

#include "texwarp/core/dormand_prince.hpp"
#include "texwarp/core/pathline.hpp"

namespace texwarp::kernels_detail {

// Work-items: kVectorsPerItem vectors of kLanes points each, all sharing one step sequence.
inline constexpr int kLanes = 16;
inline constexpr int kVectorsPerItem = 4;
inline constexpr int kPointsPerItem = kVectorsPerItem * kLanes;

// Columns of the pair loops per block, field_evaluate's and field_evaluate_gradient's (TW_VECS·64 bytes of z per
// column, 32 KiB per block in float32).
inline constexpr int kColumnBlock = 128;
// Per positional feature in field_evaluate_gradient's scratch, TW_VECS vectors in each of four arrays of n: z°,
// z°·g.x, z°·g.y and the factor f of g.
inline constexpr int kGradientArrays = 4;
// Partial row sums kept in `acc` per row, in TW_VECS vectors: R_i (complex), for v and for ∇v alike.
inline constexpr int kRowSums = 2;

// Positional feature records (reals): F(0) as hi + lo parts, then its velocity D.
inline constexpr int kRecordHiX = 0;
inline constexpr int kRecordHiY = 1;
inline constexpr int kRecordLoX = 2;
inline constexpr int kRecordLoY = 3;
inline constexpr int kRecordVelocityX = 4;
inline constexpr int kRecordVelocityY = 5;
inline constexpr int kPositionalStride = 6;
// Gradient feature records: the same six, then its rate κ (Eq. 4: v_g = D_g + κ_g·(p − F_g)).
inline constexpr int kRecordRateX = 6;
inline constexpr int kRecordRateY = 7;
inline constexpr int kGradientStride = 8;
// Pair records: four SoA arrays of pairs16 reals each, at these multiples of pairs16: ΔF(0), ΔD (x, y each).
inline constexpr int kPairStartX = 0;
inline constexpr int kPairStartY = 1;
inline constexpr int kPairVelocityX = 2;
inline constexpr int kPairVelocityY = 3;
inline constexpr int kPairArrays = 4;
// Near-collision event records: (t*, width).
inline constexpr int kEventTime = 0;
inline constexpr int kEventWidth = 1;
inline constexpr int kEventStride = 2;

// Per work-item in the status buffer: a PathlineStatus code, then the number of field evaluations per point.
inline constexpr int kStatusCode = 0;
inline constexpr int kStatusEvaluations = 1;
inline constexpr int kStatusStride = 2;
enum class PathlineStatus { kOk = 0, kNonFinite = 1, kStepCollapse = 2, kTooManySteps = 3 };
// Steps per pathline before kTooManySteps.
inline constexpr int kMaxSteps = 1000000;
// Per point in the Jacobian output: ∂x/∂x, ∂y/∂x, ∂x/∂y, ∂y/∂y.
inline constexpr int kJacobianComponents = 4;

// How the kernel raises q to h = α/2: the common α get sqrt/multiply forms (exact at 0 and ∞, no log).
enum class PowMode { kGeneral = 0, kAlpha2 = 1, kAlpha3 = 2, kAlpha3Halves = 3, kAlpha1 = 4, kAlpha4 = 5 };

// Clamps of the kernel's arithmetic, per precision: the largest relative weight z (TW_ZMAX); squared distances
// below TW_R_FLAT count as "at the feature" for ∇ln w; the smallest step before kStepCollapse (the CPU's in double).
inline constexpr double kZMaxFloat = 1e15;
inline constexpr double kZMaxDouble = 1e150;
inline constexpr double kRFlatFloat = 1e-30;
inline constexpr double kRFlatDouble = 1e-280;
inline constexpr double kMinStepFloat = 1e-6;
inline constexpr double kMinStepDouble = dormand_prince::kMinStep;

// One entry of the prelude: an integer, a real, or a real array (an initializer list, `row` values per inner
// brace when nonzero). A value may differ between the float and the double program.
struct KernelConstant {
  enum class Kind { kInt, kReal, kRealArray };
  std::string_view name;
  Kind kind;
  double float_value = 0;
  double double_value = 0;
  std::span<const double> values = {};
  std::size_t row = 0;
};

constexpr KernelConstant integer(std::string_view name, int value) {
  return {name, KernelConstant::Kind::kInt, double(value), double(value)};
}
template <class Enum>
constexpr KernelConstant integer(std::string_view name, Enum value) {
  return integer(name, static_cast<int>(value));
}
constexpr KernelConstant integer(std::string_view name, int float_value, int double_value) {
  return {name, KernelConstant::Kind::kInt, double(float_value), double(double_value)};
}
constexpr KernelConstant real(std::string_view name, double value) {
  return {name, KernelConstant::Kind::kReal, value, value};
}
constexpr KernelConstant real(std::string_view name, double float_value, double double_value) {
  return {name, KernelConstant::Kind::kReal, float_value, double_value};
}
constexpr KernelConstant real_array(std::string_view name, std::span<const double> values, std::size_t row = 0) {
  return {name, KernelConstant::Kind::kRealArray, 0, 0, values, row};
}

// The contract. Adding a constant: define it above (when the host uses it too) and add its line here; the kernel
// then sees it under its TW_ name.
inline constexpr auto kKernelConstants = std::to_array<KernelConstant>({
    integer("TW_LANES", kLanes),
    integer("TW_VECS", kVectorsPerItem),
    integer("TW_COLUMN_BLOCK", kColumnBlock),
    integer("TW_GRADIENT_ARRAYS", kGradientArrays),
    integer("TW_ROW_SUMS", kRowSums),
    integer("TW_REC_HI_X", kRecordHiX),
    integer("TW_REC_HI_Y", kRecordHiY),
    integer("TW_REC_LO_X", kRecordLoX),
    integer("TW_REC_LO_Y", kRecordLoY),
    integer("TW_REC_D_X", kRecordVelocityX),
    integer("TW_REC_D_Y", kRecordVelocityY),
    integer("TW_REC_KAPPA_X", kRecordRateX),
    integer("TW_REC_KAPPA_Y", kRecordRateY),
    integer("TW_POS_STRIDE", kPositionalStride),
    integer("TW_GRAD_STRIDE", kGradientStride),
    integer("TW_PAIR_F0_X", kPairStartX),
    integer("TW_PAIR_F0_Y", kPairStartY),
    integer("TW_PAIR_DD_X", kPairVelocityX),
    integer("TW_PAIR_DD_Y", kPairVelocityY),
    integer("TW_EVENT_TIME", kEventTime),
    integer("TW_EVENT_WIDTH", kEventWidth),
    integer("TW_EVENT_STRIDE", kEventStride),
    integer("TW_STATUS_CODE", kStatusCode),
    integer("TW_STATUS_EVALUATIONS", kStatusEvaluations),
    integer("TW_STATUS_STRIDE", kStatusStride),
    integer("TW_STATUS_OK", PathlineStatus::kOk),
    integer("TW_STATUS_NON_FINITE", PathlineStatus::kNonFinite),
    integer("TW_STATUS_STEP_COLLAPSE", PathlineStatus::kStepCollapse),
    integer("TW_STATUS_TOO_MANY_STEPS", PathlineStatus::kTooManySteps),
    integer("TW_MAX_STEPS", kMaxSteps),
    integer("TW_JACOBIAN_COMPONENTS", kJacobianComponents),
    integer("TW_POW_GENERAL", PowMode::kGeneral),
    integer("TW_POW_ALPHA2", PowMode::kAlpha2),
    integer("TW_POW_ALPHA3", PowMode::kAlpha3),
    integer("TW_POW_ALPHA1_5", PowMode::kAlpha3Halves),
    integer("TW_POW_ALPHA1", PowMode::kAlpha1),
    integer("TW_POW_ALPHA4", PowMode::kAlpha4),
    real("TW_ZMAX", kZMaxFloat, kZMaxDouble),
    real("TW_R_FLAT", kRFlatFloat, kRFlatDouble),
    real("TW_MIN_STEP", kMinStepFloat, kMinStepDouble),
    real("TW_JACOBIAN_ERROR_LENGTH", kJacobianErrorLengthPx),
    integer("TW_DP_STAGES", dormand_prince::kStages),
    real_array("TW_DP_C", dormand_prince::kC),
    real_array("TW_DP_A",
               std::span<const double>(&dormand_prince::kA[0][0],
                                       std::size(dormand_prince::kA) * std::size(dormand_prince::kA[0])),
               std::size(dormand_prince::kA[0])),
    real_array("TW_DP_E", dormand_prince::kE),
    real("TW_SAFETY", dormand_prince::kSafety),
    real("TW_MAX_GROWTH", dormand_prince::kMaxGrowth),
    real("TW_MAX_SHRINK", dormand_prince::kMaxShrink),
});

}  // namespace texwarp::kernels_detail
