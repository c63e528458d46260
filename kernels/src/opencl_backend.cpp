// The OpenCL backend factory, the device listing and the warm-up: see opencl_backend.hpp.
#include "texwarp/kernels/opencl_backend.hpp"

#include <vector>

#include "kernel_warmup.hpp"
#include "opencl_device.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {

std::unique_ptr<WarpBackend> make_opencl_backend(const OpenClOptions& options) {
  return std::make_unique<OpenClWarpBackend>(options);
}

std::vector<std::string> list_opencl_devices() { return kernels_detail::describe_devices(); }

OpenClWarmth warm_opencl_programs(const OpenClOptions& options) {
  using kernels_detail::KernelVariant;
  const kernels_detail::DeviceHandle device = kernels_detail::select_device(options);
  std::vector<KernelVariant> variants;
  for (const bool jacobian : {false, true}) {
    if (options.precision != OpenClPrecision::kDouble) variants.push_back({false, jacobian});
    if (options.precision != OpenClPrecision::kFloat && device.has_fp64) variants.push_back({true, jacobian});
  }
  // One after another in the device's shared context: PoCL 3.1 compiles under a process-wide lock, so threads
  // (each variant in a context of its own) measured no faster.
  const std::size_t files_before = kernels_detail::driver_cache_files();
  for (const KernelVariant& v : variants) kernels_detail::launch_variant_once(device, v);
  const std::size_t files_after = kernels_detail::driver_cache_files();
  return {variants.size(), files_after > files_before ? files_after - files_before : 0};
}

}  // namespace texwarp
