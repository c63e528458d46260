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

void check_device(const proto::DeviceSpec& device, const InputLocation& where) {
  if (device.kind == proto::DeviceSpec::Kind::kOpenCl && !has_opencl()) {
    throw InputError(where, "this build has no OpenCL backend: use \"cpu\" (or leave \"device\" out)");
  }
}

BackendCache::BackendCache(std::optional<proto::DeviceSpec> default_device_spec)
    : default_(default_device_spec     ? std::move(*default_device_spec)
               : has_opencl() ? proto::DeviceSpec::opencl()
                              : proto::DeviceSpec::cpu()) {
  check_device(default_, {});
}

WarpBackend& BackendCache::get(const std::optional<proto::DeviceSpec>& device, const InputLocation& where) {
  const proto::DeviceSpec& chosen = device ? *device : default_;
  check_device(chosen, where);
  const std::string key = chosen.str();
  auto it = backends_.find(key);
  if (it != backends_.end()) return *it->second;
  std::unique_ptr<WarpBackend> backend;
  if (chosen.kind == proto::DeviceSpec::Kind::kCpu) {
    backend = std::make_unique<CpuBackend>();
  } else {
#ifdef TEXWARP_HAVE_OPENCL
    OpenClOptions options;
    options.device = chosen.name;
    try {
      backend = make_opencl_backend(options);
    } catch (const OpenClNoMatchingDevice& e) {
      // A device name that matches no device is the caller's mistake (the message lists the devices there
      // are); any other OpenCL failure stays the backend's own.
      throw InputError(where, e.what());
    }
#endif
  }
  return *backends_.emplace(key, std::move(backend)).first->second;
}

}  // namespace texwarp::runner
