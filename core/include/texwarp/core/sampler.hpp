// Image sampling at continuous pixel positions (centre of pixel (i, j) at (i + 0.5, j + 0.5)): bilinear and
// bicubic (Catmull–Rom, Keys a = −1/2), with transparent, clamp or repeat borders.
#pragma once

#include "texwarp/core/image.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/proto/output_enums.hpp"

namespace texwarp {

// The job contract's enums (names: proto/output_enums.hpp).
using proto::Border;
using proto::Interpolation;

// Writes image.channels values for position p into out. kTransparent reads zeros outside the image (all
// channels, alpha included: with associated alpha this fades to transparent).
void sample_image(const Image& image, Point p, Interpolation interpolation, Border border, float* out);

// The texel that integer index i (of an axis `size` texels long) reads under `border`; −1: outside, reads zero.
int border_texel(int i, int size, Border border);

}  // namespace texwarp
