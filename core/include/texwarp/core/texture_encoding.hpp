// How a texture's values are encoded, by role (proto/image_role.hpp), and the passes around a warp's resampling that
// make filtering right for each: colour decoded from its colour space to linear light and encoded back; data as it
// is; tangent-space normals decoded to vectors, then turned and scaled with the texture (the inverse map's Jacobian),
// renormalised and encoded back.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "texwarp/core/image.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/point.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/image_role.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp {

using proto::ImageRole;
using proto::NormalConvention;

using proto::kLinearColorSpace;
using proto::kSrgbColorSpace;

// What an input's values are and how they are filtered.
struct TextureEncoding {
  ImageRole role = ImageRole::kData;
  // kColor: kSrgbColorSpace, kLinearColorSpace or a space of OpenColorIO's config (filtered in its scene-linear
  // role); empty for data and normals
  std::string color_space;
  NormalConvention normal_convention = NormalConvention::kOpenGl;  // kNormal
};

// The encoding of a file with `header`: `role` when given, else colour for an integer file (8/16 bits) or one that
// declares an sRGB space, data for a float file or one that declares a data space (proto::is_data_color_space's
// names, or a space the OpenColorIO config marks `isdata`, whatever its name); a colour's space is `color_space` when
// given, else the file's declared one, else sRGB for integer and linear for float files. A name other than sRGB's and
// linear's is looked up in OpenColorIO's config ($OCIO, else OpenImageIO's built-in one; through the image module).
// InputError at `where` (the flag or JSON path) for a colour space that is not known, or a normal map with fewer than
// three colour channels.
TextureEncoding resolve_texture_encoding(const ImageHeader& header, std::optional<ImageRole> role,
                                         const std::string& color_space, NormalConvention convention,
                                         const InputLocation& where_role, const InputLocation& where_color_space);

// What the passes found in the source.
struct TextureDecodeStats {
  std::size_t repaired_normals = 0;  // texels of a normal map of zero length or pointing below the surface
};

// Whether the values are decoded for filtering: colour not in linear light, normals (data and linear colour are
// filtered as they are).
bool decodes_values(const TextureEncoding& encoding);

// Decodes `image` in place for filtering: colour to linear light, normals to unit vectors (x right, y down the rows,
// z out of the surface), invalid ones repaired and counted in `stats`; alpha stays associated.
void decode_texture(Image& image, const TextureEncoding& encoding, const RunControl& control,
                    TextureDecodeStats& stats);

// Encodes a resampled image back in place: colour to its space; normals turned and scaled with the texture by the
// inverse map's Jacobian at each output pixel (`positions`: the row-major source positions of the output's centres;
// slopes per pixel of each image, as normals derived again from heights warped with the texture), renormalised and
// stored as (n + 1) / 2.
void encode_texture(Image& image, const TextureEncoding& encoding, const std::vector<Point>& positions,
                    const RunControl& control);

// The sRGB transfer functions (IEC 61966-2-1).
float srgb_to_linear(float v);
float linear_to_srgb(float v);

}  // namespace texwarp
