// The OpenCL backend factory and the device listing: see opencl_backend.hpp.
#include "texwarp/kernels/opencl_backend.hpp"

#include "opencl_device.hpp"
#include "pathline_program.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {

std::unique_ptr<WarpBackend> make_opencl_backend(const OpenClOptions& options) {
  return std::make_unique<OpenClWarpBackend>(options);
}

std::vector<std::string> list_opencl_devices() { return kernels_detail::describe_devices(); }

void warm_opencl_programs(const OpenClOptions& options) {
  const kernels_detail::DeviceHandle device = kernels_detail::select_device(options);
  for (const bool jacobian : {false, true}) {
    if (options.precision != OpenClPrecision::kDouble) kernels_detail::pathline_program(device, {false, jacobian});
    if (options.precision != OpenClPrecision::kFloat && device.has_fp64) {
      kernels_detail::pathline_program(device, {true, jacobian});
    }
  }
}

}  // namespace texwarp
