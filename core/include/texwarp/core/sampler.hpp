// Image sampling at continuous pixel positions (centre of pixel (i, j) at (i + 0.5, j + 0.5)): bilinear and
// bicubic (Catmull–Rom, Keys a = −1/2), with transparent, clamp or repeat borders.
#pragma once

#include <string>

#include "texwarp/core/image.hpp"
#include "texwarp/core/point.hpp"

namespace texwarp {

enum class Interpolation { kBilinear, kBicubic };
enum class Border { kTransparent, kClamp, kRepeat };

// Writes image.channels values for position p into out. kTransparent reads zeros outside the image (all
// channels, alpha included: with associated alpha this fades to transparent).
void sample_image(const Image& image, Point p, Interpolation interpolation, Border border, float* out);

Interpolation parse_interpolation(const std::string& name);  // "bilinear" | "bicubic"
Border parse_border(const std::string& name);                // "transparent" | "clamp" | "repeat"
const char* to_string(Interpolation interpolation);
const char* to_string(Border border);

}  // namespace texwarp
