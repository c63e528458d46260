// Decoding the pathline kernel's status words: see pathline_status.hpp.
#include "pathline_status.hpp"

#include <cstdio>

#include "texwarp/core/numerical_error.hpp"

namespace texwarp::kernels_detail {

std::string describe_failure(PathlineStatus status, double x, double y) {
  char where[96];
  std::snprintf(where, sizeof where, "(%.6g, %.6g)", x, y);
  switch (status) {
    case PathlineStatus::kNonFinite:
      return std::string("pathline integration on the OpenCL device produced a non-finite value for a point near ") +
             where;
    case PathlineStatus::kStepCollapse:
      return std::string("pathline step size collapsed on the OpenCL device for a point near ") + where +
             " (the field is not smooth enough there; are two features nearly colliding?)";
    default:
      return std::string("pathline integration on the OpenCL device did not finish for a point near ") + where;
  }
}

void decode_status(std::span<const std::int32_t> words, std::span<int> evaluations,
                   const std::function<Point(std::size_t item)>& where_is) {
  for (std::size_t i = 0; i < evaluations.size(); ++i) {
    const std::int32_t code = words[i * kStatusStride + kStatusCode];
    if (code != static_cast<std::int32_t>(PathlineStatus::kOk)) {
      const Point p = where_is(i);
      throw NumericalError(describe_failure(static_cast<PathlineStatus>(code), p.real(), p.imag()));
    }
    evaluations[i] = words[i * kStatusStride + kStatusEvaluations];
  }
}

}  // namespace texwarp::kernels_detail
