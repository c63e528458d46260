// Decoding the pathline kernel's status words without OpenCL: evaluations come out per work-item, and the first
// failed work-item becomes a NumericalError that says what failed and where.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "pathline_status.hpp"
#include "texwarp/core/numerical_error.hpp"

namespace texwarp::kernels_detail {
namespace {

Point where(std::size_t item) { return {1.5 + static_cast<double>(item), 2.5}; }

std::string failure(std::vector<std::int32_t> words) {
  std::vector<int> evaluations(words.size() / kStatusStride);
  try {
    decode_status(words, evaluations, where);
  } catch (const NumericalError& e) {
    return e.what();
  }
  return "";
}

TEST(PathlineStatus, EvaluationsPerWorkItem) {
  const std::vector<std::int32_t> words = {0, 7, 0, 13, 0, 1};
  std::vector<int> evaluations(3, -1);
  decode_status(words, evaluations, where);
  EXPECT_EQ(evaluations, (std::vector<int>{7, 13, 1}));
}

TEST(PathlineStatus, FailuresNameWhatAndWhere) {
  const int collapse = static_cast<int>(PathlineStatus::kStepCollapse);
  const int non_finite = static_cast<int>(PathlineStatus::kNonFinite);
  const int too_many = static_cast<int>(PathlineStatus::kTooManySteps);
  EXPECT_EQ(failure({0, 7, collapse, 13}),
            "pathline step size collapsed on the OpenCL device for a point near (2.5, 2.5) (the field is not smooth "
            "enough there; are two features nearly colliding?)");
  EXPECT_EQ(failure({non_finite, 1, collapse, 1}),
            "pathline integration on the OpenCL device produced a non-finite value for a point near (1.5, 2.5)");
  EXPECT_EQ(failure({0, 1, 0, 1, too_many, 1}),
            "pathline integration on the OpenCL device did not finish for a point near (3.5, 2.5)");
  EXPECT_EQ(failure({0, 1, 0, 1}), "");
}

}  // namespace
}  // namespace texwarp::kernels_detail
