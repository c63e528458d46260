// Render-ready texture files: tiled and MIP-mapped, the colour space recorded (OpenImageIO's make_texture, in the
// image module): a .tx path always, a TIFF or EXR output when asked (`--texture`, a job's output.texture).
#pragma once

#include <string>

#include "texwarp/core/image_io.hpp"
#include "texwarp/core/texture_encoding.hpp"

namespace texwarp {

// What a texture file holds: its pixel format and channels, its tiles' width and its MIP levels (1×1 the last).
struct WrittenTexture {
  WrittenImage image;
  int tile_width = 0;
  int mip_levels = 0;
};

// ".tx" (case-insensitive): written as a texture whatever is asked.
bool is_texture_path(const std::string& path);

// The colour space a texture records for a map of this role: the colour's space ("sRGB", "linear" or its OpenColorIO
// name); "Raw" for data and normal maps (values, not colour).
std::string texture_color_space(const TextureEncoding& encoding);

// Writes `image` atomically (temporary file, then renamed) as a texture: .tx, .tif, .tiff or .exr, else InputError
// naming the file. `format` and `encoding.compression` as write_image.
WrittenTexture write_texture(const std::string& path, const Image& image, PixelFormat format,
                             const ImageEncoding& encoding, const std::string& color_space,
                             ImageWriteTimes* times = nullptr);

// A warped map's file: write_texture when `texture` is set or the path is a .tx (recording `color_space`), else
// write_image; what the file holds either way.
WrittenImage write_output_image(const std::string& path, const Image& image, PixelFormat format,
                                const ImageEncoding& encoding, bool texture, const std::string& color_space,
                                ImageWriteTimes* times = nullptr);

}  // namespace texwarp
