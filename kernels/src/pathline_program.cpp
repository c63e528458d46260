// Building the pathline program for a kernel variant: see pathline_program.hpp.
#include "pathline_program.hpp"

#include "kernel_source.hpp"
#include "opencl_calls.hpp"
#include "pathline_kernel_args.hpp"

namespace texwarp::kernels_detail {

std::string pathline_program_text(KernelVariant variant) {
  return kernel_prelude(variant) + std::string(pathline_program_source());
}

cl::Program pathline_program(const DeviceHandle& device, KernelVariant variant) {
  cl::Program program = build_program(device, pathline_program_text(variant), "-cl-kernel-arg-info");
  with_cl_errors("inspecting the OpenCL pathline kernel on " + device.device_name, [&] {
    // The parameters' names and kinds do not depend on the real type.
    PathlineKernelArgs<float>::check(cl::Kernel(program, kPathlineKernelName.data()), kPathlineKernelName);
  });
  return program;
}

}  // namespace texwarp::kernels_detail
