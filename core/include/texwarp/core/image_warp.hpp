// The image warp: every output pixel pulls its source position through the inverse map (any backend) and
// samples the source image there; by default through the certified lattice (certified_warp.hpp), or with a
// pathline per pixel when `exact` is set; a warp whose field is zero takes its closed form (closed_form_warp.hpp).
#pragma once

#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/image.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

struct ImageWarpOptions {
  int width = 0;  // output size; 0: the source's
  int height = 0;
  Interpolation interpolation = Interpolation::kBilinear;
  Border border = Border::kTransparent;
  bool exact = false;                      // a pathline per output pixel instead of the certified lattice
  double tolerance_px = 0.05;              // the lattice's bound on the inverse map's error per pixel
  std::size_t certificate_samples = 1024;  // random pixels checked by their own pathline
};

// Where warp_image's time went: the inverse map of the output pixels (pathlines, lattice, certificate; or the
// closed form), then resampling the source.
struct ImageWarpTimes {
  double map_s = 0.0;
  double sampling_s = 0.0;
};

// With kTransparent and a source without alpha, the output gains an alpha channel (coverage), so that what
// lies outside the source is transparent rather than black.
// `certificate`, when given, receives what the warp showed about its accuracy and folds; `times` its durations.
Image warp_image(WarpBackend& backend, const WarpProblem& problem, const Image& source, const ImageWarpOptions& options,
                 const RunControl& control = {}, WarpCertificate* certificate = nullptr,
                 ImageWarpTimes* times = nullptr);

// Samples `source` at precomputed source positions (row-major, width·height of them); adds coverage alpha
// like warp_image.
Image resample_image(const Image& source, const std::vector<Point>& positions, int width, int height,
                     Interpolation interpolation, Border border);

}  // namespace texwarp
