// The image warp: every output pixel pulls its source position through the inverse map (any backend) and
// samples the source image there.
#pragma once

#include "texwarp/core/image.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

struct ImageWarpOptions {
  int width = 0;   // output size; 0: the source's
  int height = 0;
  Interpolation interpolation = Interpolation::kBilinear;
  Border border = Border::kTransparent;
};

// With kTransparent and a source without alpha, the output gains an alpha channel (coverage), so that what
// lies outside the source is transparent rather than black.
Image warp_image(WarpBackend& backend, const WarpProblem& problem, const Image& source,
                 const ImageWarpOptions& options, const RunControl& control = {});

// Samples `source` at precomputed source positions (row-major, width·height of them).
Image resample_image(const Image& source, const std::vector<Point>& positions, int width, int height,
                     Interpolation interpolation, Border border);

}  // namespace texwarp
