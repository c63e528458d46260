// run_map_pipeline: every map decoded, sampled and written in order; each write but the last runs while the next
// map is decoded (a write that waits for that decode to begin would otherwise never see it); a failing decode is
// rethrown only once the write in flight has finished; the waited seconds are one per map.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "texwarp/core/map_pipeline.hpp"

namespace texwarp {
namespace {

using namespace std::chrono_literals;

// Waits up to `limit` for `flag`.
bool wait_for(const std::atomic<bool>& flag, std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!flag.load() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(1ms);
  return flag.load();
}

TEST(MapPipeline, EachWriteOverlapsTheNextMapsDecode) {
  constexpr std::size_t kMaps = 4;
  std::mutex m;
  std::vector<std::string> events;
  const auto log = [&](const std::string& e) {
    std::lock_guard lock(m);
    events.push_back(e);
  };
  std::array<std::atomic<bool>, kMaps> decoding{};
  std::array<bool, kMaps> write_saw_next_decode{};
  MapPipelineSteps steps;
  steps.decode = [&](std::size_t i) {
    decoding[i] = true;
    log("decode " + std::to_string(i));
    Image image(2, 1, 1);
    image.pixels[0] = static_cast<float>(i);
    return image;
  };
  steps.sample = [&](std::size_t i, Image source) {
    EXPECT_EQ(source.pixels[0], static_cast<float>(i));  // its own source
    log("sample " + std::to_string(i));
    source.pixels[1] = 10.0F * static_cast<float>(i);
    return source;
  };
  steps.write = [&](std::size_t i, const Image& output) {
    EXPECT_EQ(output.pixels[1], 10.0F * static_cast<float>(i));  // its own output
    // Run beside the next decode: it begins while this write waits (in turn it would never begin).
    if (i + 1 < kMaps) write_saw_next_decode[i] = wait_for(decoding[i + 1], 5000ms);
    log("write " + std::to_string(i));
  };
  const std::vector<double> waited = run_map_pipeline(kMaps, steps);
  ASSERT_EQ(waited.size(), kMaps);
  for (const double w : waited) EXPECT_GE(w, 0.0);
  for (std::size_t i = 0; i + 1 < kMaps; ++i) EXPECT_TRUE(write_saw_next_decode[i]) << "map " << i;
  // Per map: decode, sample, write in that order; sampling in map order.
  const auto at = [&](const std::string& e) { return std::find(events.begin(), events.end(), e) - events.begin(); };
  ASSERT_EQ(events.size(), 3 * kMaps);
  for (std::size_t i = 0; i < kMaps; ++i) {
    const std::string n = std::to_string(i);
    EXPECT_LT(at("decode " + n), at("sample " + n));
    EXPECT_LT(at("sample " + n), at("write " + n));
    if (i > 0) {
      EXPECT_LT(at("sample " + std::to_string(i - 1)), at("sample " + n));
    }
  }
}

TEST(MapPipeline, AFailingDecodeIsRethrownOnceTheWriteInFlightIsDone) {
  std::atomic<bool> written{false};
  std::atomic<bool> writing{false};
  MapPipelineSteps steps;
  steps.decode = [&](std::size_t i) {
    if (i == 1) {
      EXPECT_TRUE(wait_for(writing, 5000ms));  // map 0's write has begun
      throw std::runtime_error("map 1 does not decode");
    }
    return Image(1, 1, 1);
  };
  steps.sample = [](std::size_t, Image source) { return source; };
  steps.write = [&](std::size_t i, const Image&) {
    writing = true;
    std::this_thread::sleep_for(50ms);
    if (i == 0) written = true;
  };
  try {
    run_map_pipeline(3, steps);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "map 1 does not decode");
    EXPECT_TRUE(written.load()) << "returned while map 0 was still being written";
  }
}

TEST(MapPipeline, WaitedShareCountsTheUnhiddenPartOfAWrite) {
  EXPECT_DOUBLE_EQ(waited_share(2.0, 0.5), 0.25);
  EXPECT_DOUBLE_EQ(waited_share(2.0, 3.0), 1.0);  // waited longer than it worked (thread start, rounding)
  EXPECT_DOUBLE_EQ(waited_share(0.0, 0.0), 1.0);
}

}  // namespace
}  // namespace texwarp
