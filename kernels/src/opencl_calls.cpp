// The OpenCL calls the kernels library shares: see opencl_calls.hpp.
#include "opencl_calls.hpp"

namespace texwarp::kernels_detail {
std::string describe_cl_error(const cl::Error& error) {
  const char* name = "unknown error";
  switch (error.err()) {
    case CL_DEVICE_NOT_FOUND:
      name = "CL_DEVICE_NOT_FOUND";
      break;
    case CL_DEVICE_NOT_AVAILABLE:
      name = "CL_DEVICE_NOT_AVAILABLE";
      break;
    case CL_COMPILER_NOT_AVAILABLE:
      name = "CL_COMPILER_NOT_AVAILABLE";
      break;
    case CL_MEM_OBJECT_ALLOCATION_FAILURE:
      name = "CL_MEM_OBJECT_ALLOCATION_FAILURE";
      break;
    case CL_OUT_OF_RESOURCES:
      name = "CL_OUT_OF_RESOURCES";
      break;
    case CL_OUT_OF_HOST_MEMORY:
      name = "CL_OUT_OF_HOST_MEMORY";
      break;
    case CL_BUILD_PROGRAM_FAILURE:
      name = "CL_BUILD_PROGRAM_FAILURE";
      break;
    case CL_INVALID_VALUE:
      name = "CL_INVALID_VALUE";
      break;
    case CL_INVALID_DEVICE:
      name = "CL_INVALID_DEVICE";
      break;
    case CL_INVALID_BUILD_OPTIONS:
      name = "CL_INVALID_BUILD_OPTIONS";
      break;
    case CL_INVALID_KERNEL_NAME:
      name = "CL_INVALID_KERNEL_NAME";
      break;
    case CL_INVALID_KERNEL_ARGS:
      name = "CL_INVALID_KERNEL_ARGS";
      break;
    case CL_INVALID_ARG_SIZE:
      name = "CL_INVALID_ARG_SIZE";
      break;
    case CL_INVALID_WORK_GROUP_SIZE:
      name = "CL_INVALID_WORK_GROUP_SIZE";
      break;
    case CL_INVALID_GLOBAL_WORK_SIZE:
      name = "CL_INVALID_GLOBAL_WORK_SIZE";
      break;
    case CL_INVALID_BUFFER_SIZE:
      name = "CL_INVALID_BUFFER_SIZE";
      break;
    case kPlatformNotFound:
      name = "CL_PLATFORM_NOT_FOUND_KHR";
      break;
    default:
      break;
  }
  return std::string(error.what()) + ": " + name + " (" + std::to_string(error.err()) + ")";
}

QueueDrain::~QueueDrain() {
  try {
    queue_.finish();
  } catch (const cl::Error&) {
  }
}

KernelParameters kernel_parameters(const cl::Kernel& kernel) {
  KernelParameters p;
  p.count = kernel.getInfo<CL_KERNEL_NUM_ARGS>();
  try {
    for (cl_uint i = 0; i < p.count; ++i) {
      std::string name = kernel.getArgInfo<CL_KERNEL_ARG_NAME>(i);
      while (!name.empty() && name.back() == '\0') name.pop_back();
      p.names.push_back(std::move(name));
      p.global.push_back(kernel.getArgInfo<CL_KERNEL_ARG_ADDRESS_QUALIFIER>(i) == CL_KERNEL_ARG_ADDRESS_GLOBAL);
    }
  } catch (const cl::Error& e) {
    if (e.err() != CL_KERNEL_ARG_INFO_NOT_AVAILABLE) throw;
    return {p.count, {}, {}};  // built without -cl-kernel-arg-info
  }
  return p;
}

}  // namespace texwarp::kernels_detail
