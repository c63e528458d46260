// The pathline program: the contract's prelude for a kernel variant followed by kernels/cl/*.cl, built once per
// device and variant, with its flow_pathlines kernel's parameter list checked against PathlineKernelArgs.
#pragma once

#include <CL/opencl.hpp>

#include <string>

#include "kernel_prelude.hpp"
#include "opencl_device.hpp"

namespace texwarp::kernels_detail {

// kernel_prelude(variant) followed by the embedded kernels/cl/*.cl sources.
std::string pathline_program_text(KernelVariant variant);

// Built with -cl-kernel-arg-info. Throws OpenClError when the build fails or the kernel's parameters are not
// PathlineKernelArgs'.
cl::Program pathline_program(const DeviceHandle& device, KernelVariant variant);

}  // namespace texwarp::kernels_detail
