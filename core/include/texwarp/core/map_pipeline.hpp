// A texture set's maps through one output grid in turn: each decoded, sampled and written, the write of each map but
// the last on a thread of its own while the next map is decoded (one core encodes, the other decodes). Alive together
// are one map's output and encoder's buffer and the next one's source as it is decoded (texture_set_overlap_memory),
// never two maps' resampling. Shared by the CLI's sets and the job runner's.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "texwarp/core/image.hpp"

namespace texwarp {

struct MapPipelineSteps {
  std::function<Image(std::size_t)> decode;              // map i's source
  std::function<Image(std::size_t, Image)> sample;       // map i's output from its source
  std::function<void(std::size_t, const Image&)> write;  // map i's output encoded and written (another thread)
};

// Runs maps 0 … count − 1 through `steps`; an exception from any step ends the run (after a write in flight has
// finished) and is rethrown. Returns, per map, the seconds the caller waited for its write: all of it for the last
// map, for the others the part the next map's decode did not hide.
std::vector<double> run_map_pipeline(std::size_t count, const MapPipelineSteps& steps);

// The share of a write's own `worked` seconds that counts in a budget of wall time when the caller `waited` for
// `waited` of them (1 when nothing was hidden): the stages then still add up to at most the wall time.
double waited_share(double worked, double waited);

}  // namespace texwarp
