// The flags that say what an input image holds and how it is filtered, shared by `warp` and `map-mesh`:
// `--in ROLE=PATH` (ROLE: color, data or normal; plain PATH keeps the file's default role), `--filter`,
// `--colorspace`, `--normal-convention`.
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/texture_encoding.hpp"

namespace texwarp::cli {

struct TextureFlags {
  std::string filter = "footprint";
  std::string color_space;  // empty: the file's
  std::string normal_convention = "opengl";
};

// An image argument: its role when given as ROLE=PATH.
struct RoleAndPath {
  std::optional<ImageRole> role;
  std::string path;
};

// Splits "ROLE=PATH". A prefix before '=' that is not a role is refused (InputError at `flag`, listing the roles)
// unless the whole argument names an existing file.
RoleAndPath split_role(const std::string& argument, const std::string& flag);

// Adds --filter, --colorspace and --normal-convention to `cmd`.
void add_texture_options(CLI::App& cmd, TextureFlags& flags);

// The filter and encoding the flags and the file's header give (InputError naming the flag when wrong).
SamplingFilter texture_filter(const TextureFlags& flags);
TextureEncoding texture_encoding(const ImageHeader& header, const RoleAndPath& input, const TextureFlags& flags,
                                 const std::string& flag);

}  // namespace texwarp::cli
