// Retry-After's arithmetic for a full queue: the seconds observed (a young node divides by its age, not by the whole
// 5-minute window) and the queued jobs over that throughput, clamped to 1…600 s.
#include "texwarp/server/retry_after.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace texwarp::server {
namespace {

constexpr std::int64_t kNow = 10'000'000;  // epoch ms; any fixed clock

TEST(RetryAfter, ObservedFromTheEarlierOfTheNodesStartAndTheOldestFinish) {
  EXPECT_DOUBLE_EQ(observed_seconds(kNow, kNow - 12'000, std::nullopt), 12.0);     // nothing finished: the node's age
  EXPECT_DOUBLE_EQ(observed_seconds(kNow, kNow - 100'000, kNow - 40'000), 100.0);  // finishes after the start
  // A node that joined an older farm: the farm's oldest finish in the window.
  EXPECT_DOUBLE_EQ(observed_seconds(kNow, kNow - 10'000, kNow - 200'000), 200.0);
  // At most the window, whatever the node's age.
  EXPECT_DOUBLE_EQ(observed_seconds(kNow, kNow - 3'600'000, kNow - 290'000), 300.0);
  EXPECT_DOUBLE_EQ(observed_seconds(kNow, 0, std::nullopt), 300.0);
  EXPECT_DOUBLE_EQ(observed_seconds(kNow, kNow - 3'600'000, kNow - 290'000, 60'000), 60.0);
  // At least the floor: a node up for 1.5 s is taken as up for 5 s; a clock behind the start too.
  EXPECT_DOUBLE_EQ(observed_seconds(kNow, kNow - 1'500, kNow - 1'000), kMinObservedS);
  EXPECT_DOUBLE_EQ(observed_seconds(kNow, kNow + 2'000, std::nullopt), kMinObservedS);
}

TEST(RetryAfter, QueuedJobsOverTheObservedThroughput) {
  EXPECT_EQ(retry_after_from_throughput(1, 3, 300.0), 100);  // 3 in 5 minutes: 0.01/s
  EXPECT_EQ(retry_after_from_throughput(2, 3, 6.0), 4);      // 0.5/s
  EXPECT_EQ(retry_after_from_throughput(1, 3, 10.0), 4);     // 3.33 s, rounded up
  EXPECT_EQ(retry_after_from_throughput(7, 4, 8.0), 14);
  EXPECT_EQ(retry_after_from_throughput(30, 600, 300.0), 15);
  // The young server of the review: 3 jobs in its first 6 s, 2 queued. Over the whole window it would say 200.
  EXPECT_EQ(retry_after_from_throughput(2, 3, observed_seconds(kNow, kNow - 6'000, kNow - 4'000)), 4);
}

TEST(RetryAfter, ClampedToOneToSixHundredSeconds) {
  EXPECT_EQ(retry_after_from_throughput(0, 5, 10.0), 1);
  EXPECT_EQ(retry_after_from_throughput(1, 1000, 5.0), 1);      // 0.005 s
  EXPECT_EQ(retry_after_from_throughput(1000, 3, 300.0), 600);  // 100000 s
  EXPECT_EQ(retry_after_from_throughput(601, 3, 3.0), 600);
  EXPECT_EQ(retry_after_from_throughput(600, 3, 3.0), 600);
  EXPECT_EQ(retry_after_from_throughput(599, 3, 3.0), 599);
}

TEST(RetryAfter, TooFewFinishedOrNoTimeMeansNoEstimate) {
  EXPECT_FALSE(retry_after_from_throughput(1, 0, 300.0));
  EXPECT_FALSE(retry_after_from_throughput(1, 1, 300.0));  // one job: Retry-After 300 was the bug
  EXPECT_FALSE(retry_after_from_throughput(1, kMinFinishedForRate - 1, 300.0));
  EXPECT_TRUE(retry_after_from_throughput(1, kMinFinishedForRate, 300.0));
  EXPECT_FALSE(retry_after_from_throughput(1, 5, 0.0));
  EXPECT_FALSE(retry_after_from_throughput(1, 5, -3.0));
  EXPECT_FALSE(retry_after_from_throughput(1, 5, std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(retry_after_from_throughput(1, 5, std::numeric_limits<double>::infinity()));
}

}  // namespace
}  // namespace texwarp::server
