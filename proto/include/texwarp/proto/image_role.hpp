// What an input image holds, as C++ enums with their wire names: its role (colour in a colour space, plain data,
// tangent-space normals), the colour spaces known by name and, for normal maps, which way green points. The role
// decides how a warp filters it.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "texwarp/proto/enum_names.hpp"
#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

// color: decoded from its colour space to linear light, filtered there, encoded back; data: values filtered as
// they are; normal: tangent-space normals stored as (n + 1) / 2, turned and scaled with the texture, renormalised.
enum class ImageRole { kColor, kData, kNormal };
// Which way a normal map's green channel points: OpenGL (Blender, Maya, glTF: +y up the texture, v up) or DirectX
// (Unreal, 3ds Max: green flipped, +y down the image's rows).
enum class NormalConvention { kOpenGl, kDirectX };

template <>
struct EnumNames<ImageRole> {
  static constexpr std::array<std::pair<ImageRole, const char*>, 3> kTable = {
      {{ImageRole::kColor, "color"}, {ImageRole::kData, "data"}, {ImageRole::kNormal, "normal"}}};
};

template <>
struct EnumNames<NormalConvention> {
  static constexpr std::array<std::pair<NormalConvention, const char*>, 2> kTable = {
      {{NormalConvention::kOpenGl, "opengl"}, {NormalConvention::kDirectX, "directx"}}};
};

// The longest colour space name a job may give (an OpenColorIO config's names are short: "ACES - ACEScg").
inline constexpr std::size_t kMaxColorSpaceNameBytes = 200;

// The colour spaces known without a configuration, by their canonical names (reports give these).
inline constexpr const char* kSrgbColorSpace = "sRGB";
inline constexpr const char* kLinearColorSpace = "linear";

// The canonical colour space `name` denotes (case-insensitive; also OpenImageIO's and Blender's names: "srgb_texture",
// "sRGB - Texture" and "GammaCorrected2.2" are sRGB; "lin_srgb", "lin_rec709", "scene_linear", "Linear", "Raw" and
// "Non-Color" linear), or nullopt.
TEXWARP_API std::optional<std::string> canonical_color_space(std::string_view name);
// Whether `name` declares values rather than colour ("Raw", Blender's "Non-Color", ACES 1.x configs' "Utility -
// Raw"; case-insensitive): the space texwarp records for data and normal maps, so that a file declaring it is data
// when no role is given.
TEXWARP_API bool is_data_color_space(std::string_view name);
// `"sRGB" or "linear"`: the names for a message.
TEXWARP_API std::string quoted_color_space_names();

}  // namespace texwarp::proto
