// Work split in chunks among the run's threads (RunControl): the CPU backend's batches of pathlines and the per-pixel
// passes after the map (resampling, colour and normal encoding), which are independent item by item.
#pragma once

#include <cstddef>
#include <functional>

#include "texwarp/core/run_control.hpp"

namespace texwarp {

// Calls `body(begin, end)` over [0, count) in chunks of `chunk` items, on control.thread_count() threads; checks
// cancellation before each chunk (CanceledError), reports progress after each when `report_progress` (serialised,
// the fraction of chunks done), and rethrows the first exception a chunk threw once the others have stopped.
void for_each_chunk(std::size_t count, std::size_t chunk, const RunControl& control,
                    const std::function<void(std::size_t, std::size_t)>& body, bool report_progress = false);

// Rows [0, height) in bands of a few rows, without progress: `band(y_begin, y_end)`.
void for_each_row_band(int height, const RunControl& control, const std::function<void(int, int)>& band);

}  // namespace texwarp
