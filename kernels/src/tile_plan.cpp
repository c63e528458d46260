// Cutting a pathline run into tiles: see tile_plan.hpp.
#include "tile_plan.hpp"

#include <algorithm>

#include "kernel_contract.hpp"

namespace texwarp::kernels_detail {
namespace {

std::size_t round_up(std::size_t x, std::size_t m) { return (x + m - 1) / m * m; }

}  // namespace

ScratchLayout scratch_layout(const TilePlanInput& in) {
  const std::size_t n = in.positional;
  const std::size_t lanes = kLanes;
  const std::size_t item_points = kPointsPerItem;
  // Without the Jacobian: z (n columns of one record); with it, field_evaluate_gradient's arrays; either way two
  // row sums per row when the columns take more than one block.
  const std::size_t record = in.jacobian ? kGradientArrays : 1;
  const std::size_t row_sums = kRowSums;
  const std::size_t block = kColumnBlock;
  ScratchLayout s;
  s.z_offset = round_up(2 * in.pairs16 + 2 * n + 2 * in.gradient, lanes);
  s.acc_offset = s.z_offset + record * n * item_points;
  const std::size_t acc_size = n > block ? row_sums * n * item_points : 0;
  s.stride = std::max(s.acc_offset + acc_size, lanes);
  s.item_bytes = s.stride * (in.double_precision ? sizeof(double) : sizeof(float));
  return s;
}

TilePlan plan_tiles(const TilePlanInput& in) {
  TilePlan plan;
  plan.scratch = scratch_layout(in);
  const auto n = static_cast<double>(in.positional);
  const double pair_cost = in.jacobian ? kGradientPairCost : 1.0;
  const double ops_per_item = kPointsPerItem * kEvaluationsGuess *
                              (pair_cost * (n * n + 30.0 * static_cast<double>(in.positional + in.gradient)) + 60.0);
  const std::size_t by_time = std::max<std::size_t>(1, static_cast<std::size_t>(kOpsPerTile / ops_per_item));
  const std::size_t units = std::max(1u, in.compute_units);
  // The budget, or one work-item per compute unit where that is more (within the ceiling).
  const std::size_t per_unit = std::min(units * plan.scratch.item_bytes, kScratchCeilingBytes);
  const std::size_t memory = std::min(std::max(kScratchBudgetBytes, per_unit), in.max_alloc_bytes);
  const std::size_t by_memory = std::max<std::size_t>(1, memory / plan.scratch.item_bytes);
  const std::size_t min_items = kMinItemsPerComputeUnit * units;
  plan.items_per_tile = std::min({in.items, by_memory, std::max(by_time, min_items)});
  for (std::size_t first = 0; first < in.items; first += plan.items_per_tile) {
    plan.tiles.push_back({first, std::min(plan.items_per_tile, in.items - first)});
  }
  return plan;
}

}  // namespace texwarp::kernels_detail
