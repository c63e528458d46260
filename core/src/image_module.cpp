// Finding and loading the image module with dlopen: see image_module.hpp.
#include "texwarp/core/image_module.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

// The folder of the binary this function was linked into (the executable, or a shared object such as _texwarp).
std::string folder_of_this_code() {
  Dl_info info{};
  if (::dladdr(reinterpret_cast<const void*>(&folder_of_this_code), &info) == 0 || info.dli_fname == nullptr) {
    return {};
  }
  std::error_code ec;
  const fs::path binary = fs::canonical(fs::path(info.dli_fname), ec);
  return ec ? fs::path(info.dli_fname).parent_path().string() : binary.parent_path().string();
}

std::mutex module_mutex;
const TexwarpImageModule* loaded = nullptr;

}  // namespace

std::vector<std::string> image_module_dirs() {
  if (const char* dir = std::getenv("TEXWARP_MODULE_DIR"); dir != nullptr && *dir != '\0') return {dir};
  std::vector<std::string> dirs;
  if (const std::string here = folder_of_this_code(); !here.empty()) {
    dirs.push_back((fs::path(here) / TEXWARP_MODULE_INSTALL_RELATIVE_DIR).lexically_normal().string());
    dirs.push_back(here);
  }
  dirs.emplace_back(TEXWARP_MODULE_BUILD_DIR);
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
    } else if (module->abi_version != TEXWARP_IMAGE_MODULE_ABI_VERSION ||
               module->struct_size < sizeof(TexwarpImageModule)) {
      why = "it was built for ABI version " + std::to_string(module->abi_version) + ", this texwarp needs " +
            std::to_string(TEXWARP_IMAGE_MODULE_ABI_VERSION);
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
