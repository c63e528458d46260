// The OpenCL backend factory and the device listing: see opencl_backend.hpp.
#include "texwarp/kernels/opencl_backend.hpp"

#include "opencl_device.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {

std::unique_ptr<WarpBackend> make_opencl_backend(const OpenClOptions& options) {
  return std::make_unique<OpenClWarpBackend>(options);
}

std::vector<std::string> list_opencl_devices() { return kernels_detail::describe_devices(); }

}  // namespace texwarp
