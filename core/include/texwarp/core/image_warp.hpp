// The image warp: every output pixel pulls its source position through the inverse map (any backend) and
// samples the source image there; by default through the certified lattice (certified_warp.hpp), or with a
// pathline per pixel when `exact` is set; a warp whose field is zero takes its closed form (closed_form_warp.hpp).
// Sampling filters over each pixel's footprint where the map minifies (footprint_sampler.hpp), in the role's
// working space (texture_encoding.hpp).
#pragma once

#include <optional>
#include <utility>
#include <vector>

#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/image.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/core/texture_encoding.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {

using proto::SamplingFilter;

// How the source is sampled: the reconstruction, the border, and whether minified pixels average their footprint.
struct SamplingOptions {
  Interpolation interpolation = Interpolation::kBilinear;
  Border border = Border::kTransparent;
  SamplingFilter filter = SamplingFilter::kFootprint;
};

// What resampling did: pixels footprint-filtered, the pyramid it built, normals repaired in the source.
struct ResampleStats {
  std::size_t footprint_pixels = 0;  // output pixels where the map minifies (averaged over their footprint)
  int pyramid_levels = 0;            // MIP levels built beyond the source
  std::size_t pyramid_bytes = 0;
  std::size_t repaired_normals = 0;  // a normal map's invalid texels (zero length, below the surface), repaired
};

struct ImageWarpOptions {
  int width = 0;  // output size; 0: the source's
  int height = 0;
  Interpolation interpolation = Interpolation::kBilinear;
  Border border = Border::kTransparent;
  SamplingFilter filter = SamplingFilter::kFootprint;
  TextureEncoding encoding;                // the source's role (default: data, its values filtered as they are)
  bool exact = false;                      // a pathline per output pixel instead of the certified lattice
  double tolerance_px = 0.05;              // the lattice's bound on the inverse map's error per pixel
  std::size_t certificate_samples = 1024;  // random pixels checked by their own pathline
};

// Where warp_image's time went: the inverse map of the output pixels (pathlines, lattice, certificate; or the
// closed form), then resampling the source.
struct ImageWarpTimes {
  double map_s = 0.0;
  double sampling_s = 0.0;
  ResampleStats sampling;  // what the sampling stage did
};

// The inverse map of a warp's output grid, computed once and sampled by any number of sources of one size (the maps
// of a texture set): the source position of every output pixel's centre, or a translation by whole pixels.
struct OutputGridMap {
  int width = 0;  // the output's size, pixels
  int height = 0;
  // A closed form that moves every pixel centre onto a pixel centre: (dx, dy), S⁻¹(p) = p + (dx, dy). Sources whose
  // role copies values (not normal maps) are then copied, not interpolated.
  std::optional<std::pair<int, int>> whole_pixel_shift;
  std::vector<Point> positions;  // row-major, width·height; empty when whole_pixel_shift serves every source
  WarpCertificate certificate;
  double map_s = 0.0;  // seconds to compute it
};

// Maps the output grid of a warp whose sources are `source_width`×`source_height` (options.width/height, when set,
// give the output's size): the certified lattice, a pathline per pixel with options.exact, or the closed form.
// `positions_needed`: build positions even for a whole-pixel translation (a normal map will sample them).
// `exact_certificate`: with options.exact, also check the per-pixel map (exact_grid_certificate).
OutputGridMap map_output_grid(WarpBackend& backend, const WarpProblem& problem, int source_width, int source_height,
                              const ImageWarpOptions& options, bool positions_needed, const RunControl& control = {},
                              bool exact_certificate = true);

// Samples `source` (of the size the grid was mapped for) through `map` with options' filter, border and role:
// warp_image's second half. `times` receives sampling_s and the sampling stats (map_s is left alone).
Image sample_output_grid(const OutputGridMap& map, Image source, const ImageWarpOptions& options,
                         const RunControl& control = {}, ImageWarpTimes* times = nullptr);

// With kTransparent and a source without alpha, the output gains an alpha channel (coverage), so that what
// lies outside the source is transparent rather than black.
// `certificate`, when given, receives what the warp showed about its accuracy and folds; `times` its durations.
// `source` is taken by value: a caller done with it moves it in, and it is then filtered (decoded for its role) in its
// own buffer, no copy made.
Image warp_image(WarpBackend& backend, const WarpProblem& problem, Image source, const ImageWarpOptions& options,
                 const RunControl& control = {}, WarpCertificate* certificate = nullptr,
                 ImageWarpTimes* times = nullptr);

// Samples `source` at precomputed source positions (row-major, width·height of them: the inverse map of the output
// pixels' centres, whose differences give each pixel's footprint); adds coverage alpha like warp_image. The role's
// decoding and encoding wrap the sampling (texture_encoding.hpp).
Image resample_image(Image source, const std::vector<Point>& positions, int width, int height,
                     const SamplingOptions& sampling, const TextureEncoding& encoding = {},
                     const RunControl& control = {}, ResampleStats* stats = nullptr);

}  // namespace texwarp
