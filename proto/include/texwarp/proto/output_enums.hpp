// The output choices of a job as C++ enums with their wire names: sampling (interpolation, border, filter), the warped
// image's pixel type, file format and compression, and the UV convention (DESIGN.md §3). The core uses these types
// directly.
#pragma once

#include <array>
#include <utility>

#include "texwarp/proto/enum_names.hpp"

namespace texwarp::proto {

enum class Interpolation { kBilinear, kBicubic };
enum class Border { kTransparent, kClamp, kRepeat };
// How an output pixel is made from the source: footprint averages the source over the pixel's footprint (the pixel
// mapped through the inverse map's Jacobian) where the map minifies, and reconstructs with the interpolation
// elsewhere; point samples the interpolation at the pixel centre's source position only (aliases where the map
// minifies).
enum class SamplingFilter { kFootprint, kPoint };
enum class PixelFormat { kUint8, kUint16, kHalf, kFloat };
enum class FileFormat { kPng, kTiff, kExr };
// Where v = 0 is: bottom_left (OBJ, DCC tools: v = 1 − y / height) or top_left (glTF: v = y / height).
enum class UvOrigin { kBottomLeft, kTopLeft };
// Lossless compression of a TIFF or EXR output: fast (zip level 1), none, or small (zip level 9).
// PNG has its own level (OutputSpec::png_compression_level).
enum class Compression { kFast, kNone, kSmall };

// zlib level of PNG outputs, 0 (stored) to 9. Default 1: on this project's textures level 1 encodes several times
// faster than libpng's default 6 for files a few percent larger; warped textures are intermediates.
inline constexpr int kDefaultPngCompressionLevel = 1;
inline constexpr int kMaxPngCompressionLevel = 9;

template <>
struct EnumNames<Interpolation> {
  static constexpr std::array<std::pair<Interpolation, const char*>, 2> kTable = {
      {{Interpolation::kBilinear, "bilinear"}, {Interpolation::kBicubic, "bicubic"}}};
};

template <>
struct EnumNames<Border> {
  static constexpr std::array<std::pair<Border, const char*>, 3> kTable = {
      {{Border::kTransparent, "transparent"}, {Border::kClamp, "clamp"}, {Border::kRepeat, "repeat"}}};
};

template <>
struct EnumNames<SamplingFilter> {
  static constexpr std::array<std::pair<SamplingFilter, const char*>, 2> kTable = {
      {{SamplingFilter::kFootprint, "footprint"}, {SamplingFilter::kPoint, "point"}}};
};

template <>
struct EnumNames<PixelFormat> {
  static constexpr std::array<std::pair<PixelFormat, const char*>, 4> kTable = {{{PixelFormat::kUint8, "uint8"},
                                                                                 {PixelFormat::kUint16, "uint16"},
                                                                                 {PixelFormat::kHalf, "half"},
                                                                                 {PixelFormat::kFloat, "float"}}};
};

template <>
struct EnumNames<FileFormat> {
  static constexpr std::array<std::pair<FileFormat, const char*>, 3> kTable = {
      {{FileFormat::kPng, "png"}, {FileFormat::kTiff, "tiff"}, {FileFormat::kExr, "exr"}}};
};

template <>
struct EnumNames<Compression> {
  static constexpr std::array<std::pair<Compression, const char*>, 3> kTable = {
      {{Compression::kFast, "fast"}, {Compression::kNone, "none"}, {Compression::kSmall, "small"}}};
};

template <>
struct EnumNames<UvOrigin> {
  static constexpr std::array<std::pair<UvOrigin, const char*>, 2> kTable = {
      {{UvOrigin::kBottomLeft, "bottom_left"}, {UvOrigin::kTopLeft, "top_left"}}};
};

}  // namespace texwarp::proto
