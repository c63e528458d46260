// declared_content_length: the Content-Length value the router's 413 and the connection's discard decision read.
#include <gtest/gtest.h>

#include <cstdint>

#include "texwarp/server/declared_length.hpp"

namespace texwarp::server {
namespace {

TEST(DeclaredLength, DigitsAreTheLengthAndAnythingElseIsNone) {
  EXPECT_EQ(declared_content_length("0"), std::uint64_t{0});
  EXPECT_EQ(declared_content_length("33554432"), std::uint64_t{33554432});
  // Leading zeros, as Beast accepts them: the fuzzer's 10 GB request wrote its length so.
  EXPECT_EQ(declared_content_length("0000000000000100000000013"), std::uint64_t{100000000013});
  EXPECT_EQ(declared_content_length("18446744073709551615"), UINT64_MAX);
  EXPECT_FALSE(declared_content_length("18446744073709551616"));  // overflows 64 bits
  EXPECT_FALSE(declared_content_length(""));
  EXPECT_FALSE(declared_content_length("12abc"));
  EXPECT_FALSE(declared_content_length(" 12"));
  EXPECT_FALSE(declared_content_length("-1"));
  EXPECT_FALSE(declared_content_length("+5"));
}

}  // namespace
}  // namespace texwarp::server
