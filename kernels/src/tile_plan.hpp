// TilePlan: how a run of the pathline kernel is cut into launches, as a pure function of the field's size, the
// kernel variant and the device's limits: each work-item's scratch layout, work-items per tile, the tiles.
#pragma once

#include <cstddef>
#include <vector>

namespace texwarp::kernels_detail {

// What the plan depends on.
struct TilePlanInput {
  std::size_t items = 0;       // work-items to run (kPointsPerItem points each)
  std::size_t positional = 0;  // n
  std::size_t gradient = 0;    // m
  std::size_t pairs16 = 0;     // n(n−1)/2 rounded up to a multiple of kLanes
  bool jacobian = false;       // field_evaluate_gradient's scratch and cost
  bool double_precision = false;
  unsigned compute_units = 1;
  std::size_t max_alloc_bytes = 0;  // the device's largest buffer
};

// One work-item's scratch, in reals from the start of its slot: cx, cy (pairs16 each), F_lo + t·D of positional
// and gradient features (2·n, 2·m), then z (or the gradient's kGradientArrays arrays) at z_offset, kLanes-
// aligned, then the partial row sums at acc_offset (only when n exceeds the pair loop's column block).
struct ScratchLayout {
  std::size_t z_offset = 0;
  std::size_t acc_offset = 0;
  std::size_t stride = 0;  // reals per work-item
  std::size_t item_bytes = 0;
};

// Work-items [first, first + count).
struct Tile {
  std::size_t first = 0;
  std::size_t count = 0;
  bool operator==(const Tile&) const = default;
};

struct TilePlan {
  ScratchLayout scratch;
  std::size_t items_per_tile = 0;  // the largest tile; every tile but the last has this many
  std::vector<Tile> tiles;         // in order, covering [0, items) exactly
};

// Launch sizing, each tile: about kOpsPerTile arithmetic operations (≈ 0.1–0.3 s on a 2-core AVX-512 CPU,
// estimated at kEvaluationsGuess field evaluations per point), scratch within kScratchBudgetBytes and the
// device's largest buffer, and at least kMinItemsPerComputeUnit work-items per compute unit (load balance).
// Where the budget holds fewer work-items than there are compute units (a work-item's pair coefficients take
// 4·n² bytes in float32: from n ≈ 3 500 on two units, 2 450 in double), a tile still gets one work-item per compute
// unit within kScratchCeilingBytes: a tile of one ran on one core.
inline constexpr double kOpsPerTile = 3e10;
inline constexpr double kEvaluationsGuess = 100.0;
inline constexpr std::size_t kScratchBudgetBytes = std::size_t{96} << 20;
inline constexpr std::size_t kScratchCeilingBytes = std::size_t{1} << 30;
inline constexpr std::size_t kMinItemsPerComputeUnit = 4;
// Per-point field work with ∇v, relative to v alone (texwarp_bench_kernels --jacobian, 200 features).
inline constexpr double kGradientPairCost = 2.7;

ScratchLayout scratch_layout(const TilePlanInput& input);

// No tiles when input.items is 0.
TilePlan plan_tiles(const TilePlanInput& input);

}  // namespace texwarp::kernels_detail
