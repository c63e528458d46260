// Finding and loading the image module with dlopen: see image_module.hpp.
#include "texwarp/core/image_module.hpp"

#include <dlfcn.h>
#include <link.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

// The folder of the binary this function was linked into (the executable, or a shared object such as _texwarp),
// canonical; empty when it cannot be known for sure. For the executable dladdr would give argv[0], which may be a
// bare or relative name resolved against the current folder (a `texwarp` folder there would then be searched):
// its link map's name is empty, and /proc/self/exe names it. A relative name is never used.
std::string folder_of_this_code() {
  Dl_info info{};
  link_map* map = nullptr;
  if (::dladdr1(reinterpret_cast<const void*>(&folder_of_this_code), &info, reinterpret_cast<void**>(&map),
                RTLD_DL_LINKMAP) == 0 ||
      map == nullptr) {
    return {};
  }
  const bool executable = map->l_name == nullptr || *map->l_name == '\0';
  const fs::path binary = executable ? fs::path("/proc/self/exe") : fs::path(map->l_name);
  if (!binary.is_absolute()) return {};
  std::error_code ec;
  const fs::path resolved = fs::canonical(binary, ec);
  return ec ? std::string() : resolved.parent_path().string();
}

// Whether `folder` lies inside the build tree (the build's module folder is searched only for binaries there).
bool in_build_tree(const std::string& folder) {
  const fs::path build = fs::path(TEXWARP_MODULE_BUILD_DIR).parent_path().parent_path();
  const auto [end, _] = std::mismatch(build.begin(), build.end(), fs::path(folder).begin(), fs::path(folder).end());
  return end == build.end();
}

std::mutex module_mutex;
const TexwarpImageModule* loaded = nullptr;

}  // namespace

std::vector<std::string> image_module_dirs() {
  if (const char* dir = std::getenv("TEXWARP_MODULE_DIR"); dir != nullptr && *dir != '\0') return {dir};
  std::vector<std::string> dirs;
  const std::string here = folder_of_this_code();
  if (!here.empty()) {
    dirs.push_back((fs::path(here) / TEXWARP_MODULE_INSTALL_RELATIVE_DIR).lexically_normal().string());
    dirs.push_back(here);
  }
  if (here.empty() || in_build_tree(here)) dirs.emplace_back(TEXWARP_MODULE_BUILD_DIR);
  return dirs;
}

const TexwarpImageModule& image_module(const std::string& what, const std::string& path) {
  const std::lock_guard lock(module_mutex);
  if (loaded) return *loaded;
  std::string tried;
  std::string why;
  for (const std::string& dir : image_module_dirs()) {
    const std::string file = (fs::path(dir) / kImageModuleFileName).string();
    std::error_code ec;
    if (!fs::exists(file, ec)) {
      if (why.empty()) why = "no such file";
      tried += (tried.empty() ? "" : ", ") + file;
      continue;
    }
    tried = file;  // the one that exists is the one that failed
    void* handle = ::dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* error = ::dlerror();
      why = error ? error : "dlopen failed";
      break;
    }
    const auto entry = reinterpret_cast<TexwarpImageModuleEntry>(::dlsym(handle, TEXWARP_IMAGE_MODULE_ENTRY));
    const TexwarpImageModule* module = entry ? entry() : nullptr;
    if (!module) {
      why = "it has no entry point " TEXWARP_IMAGE_MODULE_ENTRY;
    } else if (module->abi_version != TEXWARP_IMAGE_MODULE_ABI_VERSION) {
      why = "it was built for ABI version " + std::to_string(module->abi_version) + ", this texwarp needs " +
            std::to_string(TEXWARP_IMAGE_MODULE_ABI_VERSION);
    } else if (module->struct_size < sizeof(TexwarpImageModule)) {
      why = "its entry table has " + std::to_string(module->struct_size) + " bytes, this texwarp needs " +
            std::to_string(sizeof(TexwarpImageModule));
    } else {
      loaded = module;  // never closed: its code stays mapped for the process's lifetime
      return *loaded;
    }
    ::dlclose(handle);
    break;
  }
  throw InputError(InputLocation::file(path), what + " needs the OpenImageIO module at " + tried + ": " + why +
                                                  " (set TEXWARP_MODULE_DIR to the folder that holds " +
                                                  kImageModuleFileName + ")");
}

}  // namespace texwarp
