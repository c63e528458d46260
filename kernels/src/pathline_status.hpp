// What the pathline kernel reports per work-item (kStatusStride ints: a PathlineStatus code and the number of
// field evaluations per point), decoded: evaluations out, or a NumericalError that names the failed point.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include "kernel_contract.hpp"
#include "texwarp/core/point.hpp"

namespace texwarp::kernels_detail {

// The message for a work-item that ended with `status`, near the point (x, y) in pixels.
std::string describe_failure(PathlineStatus status, double x, double y);

// words: kStatusStride per work-item, evaluations: one per work-item. Throws NumericalError for the first
// work-item whose code is not kOk, near where_is(item).
void decode_status(std::span<const std::int32_t> words, std::span<int> evaluations,
                   const std::function<Point(std::size_t item)>& where_is);

}  // namespace texwarp::kernels_detail
