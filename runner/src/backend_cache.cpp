// Per-worker compute backends: see backend_cache.hpp.
#include "texwarp/runner/backend_cache.hpp"

#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/kernels/opencl_backend.hpp"
#include "texwarp/kernels/opencl_error.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::runner {

const char* default_device() { return "opencl"; }

void use_kernel_cache_dir(const std::string& folder) { set_opencl_cache_dir(folder); }

std::string warm_kernels(const proto::DeviceSpec& device) {
  if (device.kind == proto::DeviceSpec::Kind::kCpu) return "no kernels (cpu)";
  OpenClOptions options;
  options.device = device.name;
  const OpenClWarmth warmth = warm_opencl_programs(options);
  return std::to_string(warmth.variants) + " variants launched, " + std::to_string(warmth.files_compiled) +
         " files compiled into " + opencl_driver_cache_dir();
}

BackendCache::BackendCache(std::optional<proto::DeviceSpec> default_device_spec)
    : default_(default_device_spec ? std::move(*default_device_spec) : proto::DeviceSpec::opencl()) {}

WarpBackend& BackendCache::get(const std::optional<proto::DeviceSpec>& device, const InputLocation& where) {
  const proto::DeviceSpec& chosen = device ? *device : default_;
  const std::string key = chosen.str();
  auto it = backends_.find(key);
  if (it != backends_.end()) return *it->second;
  std::unique_ptr<WarpBackend> backend;
  if (chosen.kind == proto::DeviceSpec::Kind::kCpu) {
    backend = std::make_unique<CpuBackend>();
  } else {
    OpenClOptions options;
    options.device = chosen.name;
    try {
      backend = make_opencl_backend(options);
    } catch (const OpenClNoMatchingDevice& e) {
      // A device name that matches no device is the caller's mistake (the message lists the devices there
      // are); any other OpenCL failure stays the backend's own.
      throw InputError(where, e.what());
    }
  }
  return *backends_.emplace(key, std::move(backend)).first->second;
}

}  // namespace texwarp::runner
