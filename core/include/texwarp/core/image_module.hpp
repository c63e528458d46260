// Where core finds the image module (every format but PNG, through OpenImageIO; ABI: image_module_abi.h) and loads
// it, once per process, on the first file that needs it.
#pragma once

#include <string>
#include <vector>

#include "texwarp/core/image_module_abi.h"

namespace texwarp {

// The module's file name.
inline constexpr const char* kImageModuleFileName = "libtexwarp_image_oiio.so";

// The folders searched for the module, in order: $TEXWARP_MODULE_DIR alone when it is set; else, beside the binary
// that holds core (the executable by /proc/self/exe, or the Python extension by its absolute path; never a
// relative folder), `../<libdir>/texwarp` (an install's layout) and that folder itself (the Python package's),
// then the build tree's module folder, for binaries inside the build tree only.
std::vector<std::string> image_module_dirs();

// The loaded module. `what` says what needs it ("reading .exr", "writing .tif"), `path` is the file concerned:
// when no module can be loaded, InputError naming that file: "reading .exr needs the OpenImageIO module at
// <the paths tried>: <why>". Thread-safe; loads at most once per process (a failure is retried on the next call).
const TexwarpImageModule& image_module(const std::string& what, const std::string& path);

}  // namespace texwarp
