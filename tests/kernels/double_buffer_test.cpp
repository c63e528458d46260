// The double buffer's order of calls without OpenCL: the next tile is submitted before the current one completes,
// slots alternate, and a stop between tiles submits nothing more.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "double_buffer.hpp"

namespace texwarp::kernels_detail {
namespace {

struct NamedSlot {
  explicit NamedSlot(const std::string& prefix) : name(prefix + std::to_string(count_++)) {}
  std::string name;
  static inline int count_ = 0;
};

std::vector<std::string> trace(std::size_t tiles, std::size_t stop_before = 1000) {
  NamedSlot::count_ = 0;
  DoubleBuffer<NamedSlot> buffer(std::string("s"));
  std::vector<Tile> plan;
  for (std::size_t i = 0; i < tiles; ++i) plan.push_back({10 * i, 10});
  std::vector<std::string> log;
  std::size_t befores = 0;
  try {
    buffer.run(
        plan,
        [&] {
          if (befores++ == stop_before) throw std::runtime_error("stop");
          log.emplace_back("before");
        },
        [&](NamedSlot& s, Tile t) { log.push_back("submit " + std::to_string(t.first) + " in " + s.name); },
        [&](NamedSlot& s, Tile t) { log.push_back("complete " + std::to_string(t.first) + " in " + s.name); });
  } catch (const std::runtime_error&) {
    log.emplace_back("stopped");
  }
  return log;
}

TEST(DoubleBuffer, SubmitsTheNextTileBeforeCompletingTheCurrent) {
  const std::vector<std::string> expected = {
      "before",          "submit 0 in s0",    "before", "submit 10 in s1",  "complete 0 in s0", "before",
      "submit 20 in s0", "complete 10 in s1", "before", "complete 20 in s0"};
  EXPECT_EQ(trace(3), expected);
}

TEST(DoubleBuffer, OneTileAndNone) {
  EXPECT_EQ(trace(1), (std::vector<std::string>{"before", "submit 0 in s0", "before", "complete 0 in s0"}));
  EXPECT_TRUE(trace(0).empty());
}

TEST(DoubleBuffer, AStopBetweenTilesSubmitsNothingMore) {
  EXPECT_EQ(trace(3, 0), (std::vector<std::string>{"stopped"}));
  EXPECT_EQ(trace(3, 2), (std::vector<std::string>{"before", "submit 0 in s0", "before", "submit 10 in s1",
                                                   "complete 0 in s0", "stopped"}));
}

}  // namespace
}  // namespace texwarp::kernels_detail
