// What each latency stage of a warp costs, predicted from the work's size: one table of per-stage costs measured
// with --timings on the reference 2-core machine (stage_costs.cpp). The weights of the CLI's --progress.
#pragma once

#include <cstddef>

#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/latency_stage.hpp"

namespace texwarp::runner {

// The size of a command's work, as far as the stages' costs depend on it. The defaults: a 1024² warp with 50
// features on the certified lattice (the model's reference row).
struct StageWorkload {
  double input_pixels = 1024.0 * 1024.0;   // the decoded texture
  double output_pixels = 1024.0 * 1024.0;  // the warped image
  std::size_t maps = 1;  // a texture set's maps: each decoded, sampled, encoded and written (one grid for all)
  std::size_t features = 50;
  bool pathlines = true;  // false: a closed form or a baseline (no pathline is integrated)
  bool exact = false;     // per-pixel pathlines (--exact) instead of the lattice
  // The output pixels are `check`'s Jacobian grid: each point's pathline carries the variational equation, in
  // double precision at check's tight tolerance (far costlier per point than an --exact warp's pixels).
  bool jacobian_grid = false;
};

// An image warp's workload: the texture `input`, warped to width × height (0: the input's), with `features`
// (pathlines: the field's warp, not yet known to be a closed form).
StageWorkload image_workload(const ImageHeader& input, int width, int height, std::size_t features, bool exact);

// Predicted seconds of `stage` for `work` (> 0 for every stage, so that each moves the progress a little).
double predicted_seconds(proto::LatencyStage stage, const StageWorkload& work);

}  // namespace texwarp::runner
