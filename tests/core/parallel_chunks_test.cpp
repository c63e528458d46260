// for_each_chunk (parallel_chunks.hpp): every item once, progress that never goes back however the threads finish,
// the first exception rethrown.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "texwarp/core/parallel_chunks.hpp"

namespace texwarp {
namespace {

TEST(ParallelChunks, ProgressNeverGoesBackWhenThreadsFinishOutOfOrder) {
  // A slow progress callback makes finished chunks queue for it; each report must still be the highest count so far
  // (a count taken before the queue and reported after it went back: 0.55625 after 0.5625 in a Jacobian check).
  constexpr std::size_t kItems = 4000;
  std::vector<std::atomic<int>> seen(kItems);
  std::vector<double> reports;
  RunControl control;
  control.threads = 4;
  control.progress = [&reports](double f) {
    reports.push_back(f);
    std::this_thread::sleep_for(std::chrono::microseconds(20));
  };
  for_each_chunk(
      kItems, 4, control,
      [&seen](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) ++seen[i];
      },
      true);
  for (std::size_t i = 0; i < kItems; ++i) ASSERT_EQ(seen[i].load(), 1) << "item " << i;
  ASSERT_EQ(reports.size(), kItems / 4);
  for (std::size_t k = 0; k < reports.size(); ++k) {
    ASSERT_DOUBLE_EQ(reports[k], static_cast<double>(k + 1) / static_cast<double>(reports.size())) << "report " << k;
  }
}

TEST(ParallelChunks, TheFirstExceptionIsRethrownOnceTheOthersStop) {
  RunControl control;
  control.threads = 3;
  std::atomic<int> ran{0};
  EXPECT_THROW(for_each_chunk(1000, 1, control,
                              [&ran](std::size_t begin, std::size_t) {
                                ++ran;
                                std::this_thread::sleep_for(std::chrono::microseconds(100));
                                if (begin == 10) throw std::runtime_error("chunk 10");
                              }),
               std::runtime_error);
  EXPECT_LT(ran.load(), 1000);  // the others stopped taking chunks
}

}  // namespace
}  // namespace texwarp
