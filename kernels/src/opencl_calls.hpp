// The OpenCL calls the kernels library shares: cl::Error → OpenClError with the call's context, buffers from host
// memory and transfers of whole spans, a queue drained on every exit, and a kernel's parameter list as the device
// reports it (clGetKernelInfo, clGetKernelArgInfo).
#pragma once

#include <CL/opencl.hpp>

#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "texwarp/kernels/opencl_error.hpp"

namespace texwarp::kernels_detail {

// ocl-icd's answer when no ICD is installed (CL_PLATFORM_NOT_FOUND_KHR, cl_ext.h).
inline constexpr cl_int kPlatformNotFound = -1001;

// "clEnqueueNDRangeKernel: CL_OUT_OF_RESOURCES (-5)".
std::string describe_cl_error(const cl::Error& error);

// Runs f(); an OpenCL call in it that fails becomes OpenClError("<context>: <describe_cl_error>").
template <class F>
decltype(auto) with_cl_errors(std::string_view context, F&& f) {
  try {
    return std::forward<F>(f)();
  } catch (const cl::Error& e) {
    throw OpenClError(std::string(context) + ": " + describe_cl_error(e));
  }
}

// A read-only device buffer holding a copy of `data` (not empty).
template <class T>
cl::Buffer read_only_buffer(const cl::Context& context, std::span<const T> data) {
  return cl::Buffer(context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, data.size_bytes(), const_cast<T*>(data.data()));
}

// Non-blocking transfers of a whole span from / into the start of a buffer; `done` (optional) signals the read.
template <class T>
void enqueue_write(const cl::CommandQueue& queue, const cl::Buffer& buffer, std::span<const T> data) {
  queue.enqueueWriteBuffer(buffer, CL_FALSE, 0, data.size_bytes(), data.data());
}
template <class T>
void enqueue_read(const cl::CommandQueue& queue, const cl::Buffer& buffer, std::span<T> data,
                  cl::Event* done = nullptr) {
  queue.enqueueReadBuffer(buffer, CL_FALSE, 0, data.size_bytes(), data.data(), nullptr, done);
}

// Finishes the queue when it goes out of scope, however the scope ends (results, an exception): nothing may still
// write into host memory that the caller is about to release.
class QueueDrain {
 public:
  explicit QueueDrain(cl::CommandQueue& queue) : queue_(queue) {}
  ~QueueDrain();
  QueueDrain(const QueueDrain&) = delete;
  QueueDrain& operator=(const QueueDrain&) = delete;

 private:
  cl::CommandQueue& queue_;
};

// A kernel's parameters as the device reports them: their number always; names and whether each is a __global
// pointer when the program was built with -cl-kernel-arg-info (else `names` is empty).
struct KernelParameters {
  std::size_t count = 0;
  std::vector<std::string> names;
  std::vector<bool> global;
};
KernelParameters kernel_parameters(const cl::Kernel& kernel);

}  // namespace texwarp::kernels_detail
