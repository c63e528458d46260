// Footprint filtering of a warp's resampling: an output pixel where the inverse map minifies averages the source
// over its footprint (the pixel mapped through the inverse map's Jacobian, an ellipse), with the reconstruction
// kernel asked for (bilinear's tent, bicubic's Catmull–Rom) stretched along the ellipse's axes, on a MIP pyramid
// level chosen by the minor axis and blended with the next; where the map does not minify, the plain
// reconstruction (sampler.hpp), value for value.
#pragma once

#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

#include "texwarp/core/image.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/sampler.hpp"

namespace texwarp {

// The inverse map's Jacobian at an output pixel: the source displacement (pixels) of one output pixel's step in x
// (dx) and in y (dy).
struct PixelJacobian {
  Point dx{1.0, 0.0};
  Point dy{0.0, 1.0};
};

// The Jacobian at output pixel (x, y) of a row-major grid of source positions (width·height of them, the centres'
// inverse map): central differences between the pixel's neighbours, one-sided at the grid's edges; an axis of a
// grid one pixel wide keeps the identity's column. Each position's error (the lattice's bound ε) moves a column by at
// most ε (ε/2 + ε/2 centred), so a footprint's axes are within ε px of the exact map's.
PixelJacobian grid_jacobian(const std::vector<Point>& positions, int width, int height, int x, int y);

// The footprint's semi-axes (σ1 ≥ σ2, source pixels per output pixel) and the major axis's unit direction.
struct FootprintAxes {
  double major = 1.0;
  double minor = 1.0;
  Point major_direction{1.0, 0.0};
};
FootprintAxes footprint_axes(const PixelJacobian& jacobian);

// A pixel minifies, and is footprint-filtered, where the footprint's major semi-axis exceeds this (a 0.1 % margin
// above 1, so that an identity or a rotation measured with rounding keeps the plain reconstruction).
inline constexpr double kMinifyingMajorAxis = 1.001;
// The footprint's minor axis is widened to at least major / kMaxAnisotropy (cost bound: the taps grow with the
// ratio); OpenImageIO's TextureSystem defaults to 32, GPUs to 16.
inline constexpr double kMaxAnisotropy = 16.0;
// The pyramid level is chosen so that the footprint's minor semi-axis spans at least this many of its texels (the
// level's box prefilter then widens the kernel by at most 1/kMinorTexels of its minor axis), blended with the next
// level so that the filter changes continuously with the footprint.
inline constexpr double kMinorTexels = 2.0;

class FootprintSampler {
 public:
  // The pyramid's levels are built on first need, each once (thread-safe), so only as deep as the footprints asked
  // for go. `source` must outlive the sampler.
  FootprintSampler(const Image& source, Interpolation interpolation, Border border);

  // Writes source.channels values for the output pixel whose centre maps to `p` with the inverse Jacobian
  // `jacobian`: the plain reconstruction where the footprint's major semi-axis is at most kMinifyingMajorAxis,
  // else the footprint average. Returns whether the pixel was footprint-filtered.
  bool sample(Point p, const PixelJacobian& jacobian, float* out) const;

  // MIP levels built beyond the source itself, and their bytes (at most a third of the source's).
  int pyramid_levels() const;
  std::size_t pyramid_bytes() const;

  // The pyramid level index (0: the source) and the weight of the next level for a minor semi-axis.
  static void choose_level(double minor, int levels, int& level, double& next_weight);

 private:
  const Image& level(int l) const;
  void filter_level(int l, Point p, const FootprintAxes& axes, double* acc) const;

  const Image& source_;
  Interpolation interpolation_;
  Border border_;
  // Level 1, 2, … down to 1×1: binomial decimations of the level above, each made by the first sample that needs it.
  int max_levels_ = 0;
  mutable std::vector<std::unique_ptr<Image>> levels_;
  mutable std::unique_ptr<std::once_flag[]> built_;
};

}  // namespace texwarp
