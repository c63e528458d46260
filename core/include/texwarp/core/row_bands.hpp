// Rows of an output image shared among the run's threads in bands: for the per-pixel passes after the map
// (resampling, colour and normal encoding), which are independent pixel by pixel.
#pragma once

#include <functional>

#include "texwarp/core/run_control.hpp"

namespace texwarp {

// Calls `band(y_begin, y_end)` over [0, height) in bands of a few rows, on control.thread_count() threads; checks
// cancellation between bands (CanceledError) and rethrows the first exception a band threw.
void for_each_row_band(int height, const RunControl& control, const std::function<void(int, int)>& band);

}  // namespace texwarp
