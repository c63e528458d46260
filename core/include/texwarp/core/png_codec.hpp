// PNG files read and written with libpng directly (no OpenImageIO: PNG is the common case and must not load it).
// Decodes every PNG kind to exactly the floats OpenImageIO 2.4 gave (expanded to 8 or 16 bits, no gamma applied,
// alpha associated on the integers) and writes 8- or 16-bit files with alpha unassociated as it did.
#pragma once

#include <string>

#include "texwarp/core/image.hpp"
#include "texwarp/core/image_io.hpp"

namespace texwarp {

// The header of the PNG file at `path`, checked against `limits`; InputError naming the file otherwise.
ImageHeader read_png_header(const std::string& path, const ImageLimits& limits);

// The whole image as float, decoded a band of rows at a time as read_image promises (memory committed only for the
// rows decoded; any libpng error, or a warning once pixels are being decoded, is an InputError naming the file:
// "is truncated or corrupt: ..."; CanceledError before a band, or an interlaced image's next row in its passes, once
// `control` is cancelled).
Image read_png(const std::string& path, const ImageLimits& limits, ImageHeader* header, const RunControl& control);

// Writes `image` to `file` (no atomicity here: the caller writes a temporary file and publishes it) as 8-bit
// (uint8, half, float: PNG stores no floats, as OpenImageIO did) or 16-bit (uint16) samples, zlib level
// `compression_level`; returns what it stored (uint8 or uint16). std::runtime_error naming `name` when the file
// cannot be written.
PixelFormat write_png(const std::string& file, const std::string& name, const Image& image, PixelFormat format,
                      int compression_level);

}  // namespace texwarp
