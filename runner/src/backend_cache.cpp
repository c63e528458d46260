// Per-worker compute backends: see backend_cache.hpp.
#include "texwarp/runner/backend_cache.hpp"

#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/proto/input_error.hpp"
#ifdef TEXWARP_HAVE_OPENCL
#include "texwarp/kernels/opencl_backend.hpp"
#include "texwarp/kernels/opencl_error.hpp"
#endif

namespace texwarp::runner {

bool has_opencl() {
#ifdef TEXWARP_HAVE_OPENCL
  return true;
#else
  return false;
#endif
}

const char* default_device() { return has_opencl() ? "opencl" : "cpu"; }

void check_device(const std::string& device, const std::string& where) {
  if (device.empty() || device == "cpu") return;
  if (device == "opencl" || (device.rfind("opencl:", 0) == 0 && device.size() > 7)) {
    if (!has_opencl()) {
      throw InputError(where, "this build has no OpenCL backend: use \"cpu\" (or leave \"device\" out)");
    }
    return;
  }
  throw InputError(where, "expected \"cpu\", \"opencl\" or \"opencl:<device name>\", got \"" + device.substr(0, 80) + "\"");
}

BackendCache::BackendCache(std::string default_device_name)
    : default_(default_device_name.empty() ? default_device() : std::move(default_device_name)) {
  check_device(default_, "default device");
}

WarpBackend& BackendCache::get(const std::string& device, const std::string& where) {
  const std::string name = device.empty() ? default_ : device;
  check_device(name, where);
  auto it = backends_.find(name);
  if (it != backends_.end()) return *it->second;
  std::unique_ptr<WarpBackend> backend;
  if (name == "cpu") {
    backend = std::make_unique<CpuBackend>();
  } else {
#ifdef TEXWARP_HAVE_OPENCL
    OpenClOptions options;
    if (name.size() > 7) options.device = name.substr(7);
    try {
      backend = make_opencl_backend(options);
    } catch (const OpenClNoMatchingDevice& e) {
      // A device name that matches no device is the caller's mistake (the message lists the devices there
      // are); any other OpenCL failure stays the backend's own.
      throw InputError(where, e.what());
    }
#endif
  }
  return *backends_.emplace(name, std::move(backend)).first->second;
}

}  // namespace texwarp::runner
