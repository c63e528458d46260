// The image role and filtering flags of `warp` and `map-mesh`: see texture_flags.hpp.
#include "texture_flags.hpp"

#include <filesystem>

#include "texwarp/proto/input_error.hpp"

namespace texwarp::cli {

RoleAndPath split_role(const std::string& argument, const std::string& flag) {
  const auto eq = argument.find('=');
  if (eq == std::string::npos) return {std::nullopt, argument};
  const std::string prefix = argument.substr(0, eq);
  if (const auto role = proto::enum_from_name<ImageRole>(prefix)) return {*role, argument.substr(eq + 1)};
  std::error_code ec;
  if (std::filesystem::exists(argument, ec)) return {std::nullopt, argument};
  throw InputError(InputLocation::flag(flag), "unknown role \"" + prefix.substr(0, 40) + "\" in \"" +
                                                  argument.substr(0, 200) + "\": expected ROLE=PATH with ROLE " +
                                                  proto::quoted_enum_names<ImageRole>() + ", or a path");
}

void add_texture_options(CLI::App& cmd, TextureFlags& flags) {
  cmd.add_option("--filter", flags.filter,
                 "footprint (default: where the warp shrinks the texture, each pixel averages the source over its "
                 "footprint) or point (the interpolation at the pixel's centre only; aliases where the warp shrinks)")
      ->check(CLI::IsMember(proto::enum_names<SamplingFilter>()));
  cmd.add_option("--colorspace", flags.color_space,
                 "the colour space of a color image: sRGB or linear (default: the file's; untagged 8/16-bit files "
                 "are sRGB, float files linear); colour is filtered in linear light and encoded back");
  cmd.add_option("--normal-convention", flags.normal_convention,
                 "a normal map's green channel: opengl (default; Blender, Maya, glTF) or directx (Unreal, 3ds Max)")
      ->check(CLI::IsMember(proto::enum_names<NormalConvention>()));
}

SamplingFilter texture_filter(const TextureFlags& flags) {
  return proto::parse_enum<SamplingFilter>(flags.filter, InputLocation::flag("--filter"));
}

TextureEncoding texture_encoding(const ImageHeader& header, const RoleAndPath& input, const TextureFlags& flags,
                                 const std::string& flag) {
  const auto convention =
      proto::parse_enum<NormalConvention>(flags.normal_convention, InputLocation::flag("--normal-convention"));
  return resolve_texture_encoding(header, input.role, flags.color_space, convention, InputLocation::flag(flag),
                                  InputLocation::flag("--colorspace"));
}

}  // namespace texwarp::cli
