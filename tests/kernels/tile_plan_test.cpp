// The tile plan without OpenCL: scratch layouts computed by hand, tiles that cover the run exactly, and the
// memory, time and load-balance bounds on their size.
#include <gtest/gtest.h>

#include "kernel_contract.hpp"
#include "tile_plan.hpp"

namespace texwarp::kernels_detail {
namespace {

TilePlanInput input(std::size_t items, std::size_t n, std::size_t m, bool jacobian, bool dp) {
  TilePlanInput in;
  in.items = items;
  in.positional = n;
  in.gradient = m;
  const std::size_t pairs = n < 2 ? 0 : n * (n - 1) / 2;
  in.pairs16 = (pairs + 15) / 16 * 16;
  in.jacobian = jacobian;
  in.double_precision = dp;
  in.compute_units = 2;
  in.max_alloc_bytes = std::size_t{1} << 30;
  return in;
}

TEST(TilePlan, ScratchLayoutOfTheFieldAlone) {
  // n = 20: 190 pairs → 192; cx, cy, F_lo + t·D: 2·192 + 40 = 424 → 432; z: 20·64; no row sums (n ≤ 128).
  const ScratchLayout s = scratch_layout(input(1, 20, 0, false, false));
  EXPECT_EQ(s.z_offset, 432u);
  EXPECT_EQ(s.acc_offset, 432u + 20 * 64);
  EXPECT_EQ(s.stride, 1712u);
  EXPECT_EQ(s.item_bytes, 1712u * 4);
  // n = 130 > 128: two row sums per row.
  const ScratchLayout wide = scratch_layout(input(1, 130, 0, false, false));
  EXPECT_EQ(wide.stride - wide.acc_offset, 2u * 130 * 64);
}

TEST(TilePlan, ScratchLayoutWithTheJacobianInDouble) {
  // n = 200: 19900 pairs → 19904; 2·19904 + 400 + 2·3 = 40214 → 40224; four arrays of 200·64; two row sums per
  // row (n > 128, one column block).
  const ScratchLayout s = scratch_layout(input(1, 200, 3, true, true));
  EXPECT_EQ(s.z_offset, 40224u);
  EXPECT_EQ(s.acc_offset, 40224u + 4 * 200 * 64);
  EXPECT_EQ(s.stride, 91424u + 2 * 200 * 64);
  EXPECT_EQ(s.item_bytes, s.stride * 8);
  // 128 features fit one block: no row sums, in either precision; 129 do not.
  for (const bool dp : {false, true}) {
    EXPECT_EQ(scratch_layout(input(1, 128, 0, true, dp)).stride, scratch_layout(input(1, 128, 0, true, dp)).acc_offset);
    EXPECT_GT(scratch_layout(input(1, 129, 0, true, dp)).stride, scratch_layout(input(1, 129, 0, true, dp)).acc_offset);
  }
}

TEST(TilePlan, TilesCoverTheRunExactlyInOrder) {
  for (const std::size_t items : {1u, 7u, 64u, 1000u, 4097u}) {
    TilePlanInput in = input(items, 120, 0, false, false);
    in.max_alloc_bytes = 3'000'000;  // a small device: several tiles
    const TilePlan plan = plan_tiles(in);
    ASSERT_FALSE(plan.tiles.empty());
    std::size_t next = 0;
    for (std::size_t t = 0; t < plan.tiles.size(); ++t) {
      EXPECT_EQ(plan.tiles[t].first, next);
      EXPECT_GE(plan.tiles[t].count, 1u);
      if (t + 1 < plan.tiles.size()) {
        EXPECT_EQ(plan.tiles[t].count, plan.items_per_tile);
      }
      EXPECT_LE(plan.tiles[t].count, plan.items_per_tile);
      next += plan.tiles[t].count;
    }
    EXPECT_EQ(next, items);
  }
  EXPECT_TRUE(plan_tiles(input(0, 10, 0, false, false)).tiles.empty());
}

TEST(TilePlan, MemoryBoundsTheTile) {
  TilePlanInput in = input(100000, 20, 0, false, false);
  in.max_alloc_bytes = 1712 * 4 * 10 + 5;  // scratch of 10 work-items
  const TilePlan plan = plan_tiles(in);
  EXPECT_EQ(plan.items_per_tile, 10u);
  EXPECT_EQ(plan.tiles.size(), 10000u);
  // Never more than the budget, however large the device's buffers.
  in.max_alloc_bytes = std::size_t{1} << 40;
  EXPECT_LE(plan_tiles(in).items_per_tile * plan.scratch.item_bytes, kScratchBudgetBytes);
}

TEST(TilePlan, EveryComputeUnitGetsAWorkItemWhereOneOutgrowsTheBudget) {
  // n = 5 000 in float32: 12 497 500 pairs → 12 497 504; cx, cy and F_lo + t·D: 2·12 497 504 + 10 000 =
  // 25 005 008 reals, then z 5 000·64 and two row sums a row 2·5 000·64: 25 965 008 reals, 103 860 032 bytes,
  // above the 96 MiB budget.
  TilePlanInput in = input(1000, 5000, 0, false, false);
  const std::size_t item = scratch_layout(in).item_bytes;
  ASSERT_EQ(item, 103'860'032u);
  ASSERT_GT(item, kScratchBudgetBytes);
  EXPECT_EQ(plan_tiles(in).items_per_tile, 2u);  // one per compute unit, not one for the whole device
  in.compute_units = 16;
  EXPECT_EQ(plan_tiles(in).items_per_tile, 10u);  // 16 units, but within the 1 GiB ceiling
  in.max_alloc_bytes = item + 1;                  // the device's largest buffer holds one
  EXPECT_EQ(plan_tiles(in).items_per_tile, 1u);
  // In double from n = 3 600 (109 238 528 bytes a work-item): two a tile for two units, as in float32.
  TilePlanInput dp = input(1000, 3600, 0, false, true);
  ASSERT_GT(scratch_layout(dp).item_bytes, kScratchBudgetBytes);
  EXPECT_EQ(plan_tiles(dp).items_per_tile, 2u);
}

TEST(TilePlan, TimeBoundsTheTileButEveryComputeUnitGetsWork) {
  // n = 50: 64·100·(2500 + 1500 + 60)·... per item: 3e10 / (6400·4060) = 1154 items.
  const TilePlan by_time = plan_tiles(input(100000, 50, 0, false, false));
  EXPECT_EQ(by_time.items_per_tile, 1154u);
  // With ∇v the pair loop costs 2.7 times as much.
  const TilePlan jacobian = plan_tiles(input(100000, 50, 0, true, false));
  EXPECT_EQ(jacobian.items_per_tile, static_cast<std::size_t>(3e10 / (6400.0 * (2.7 * 4000.0 + 60.0))));
  // n = 1000: about 4 items by time, but 4 per compute unit at least (2 units).
  EXPECT_EQ(plan_tiles(input(100000, 1000, 0, false, false)).items_per_tile, 8u);
  // A small run is one tile.
  const TilePlan small = plan_tiles(input(5, 50, 0, false, false));
  ASSERT_EQ(small.tiles.size(), 1u);
  EXPECT_EQ(small.tiles[0], (Tile{0, 5}));
}

}  // namespace
}  // namespace texwarp::kernels_detail
