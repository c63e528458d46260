// BackendCache: the compute backends one worker uses, made on first use and kept (an OpenCL backend holds a
// context, a queue and built programs): "cpu" is the double-precision reference, "opencl[:<device>]" the
// kernels when this build has them. One cache per worker thread: backends are not shared between threads.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "texwarp/core/warp_backend.hpp"

namespace texwarp::runner {

// True when this build has the OpenCL backend (texwarp_kernels).
bool has_opencl();

// "opencl" when built with OpenCL, else "cpu".
const char* default_device();

// InputError at `where` unless `device` is "", "cpu", "opencl" or "opencl:<name>" and this build can run it.
void check_device(const std::string& device, const std::string& where);

class BackendCache {
 public:
  // `default_device` answers jobs that name none ("" here means default_device()).
  explicit BackendCache(std::string default_device = "");

  // The backend for `device` ("" for the default). InputError at `where` for a device this build cannot run or
  // an OpenCL device name that matches no device; the OpenCL backend's own error when the device cannot be opened.
  WarpBackend& get(const std::string& device, const std::string& where = "$.options.device");

  const std::string& default_name() const { return default_; }

 private:
  std::string default_;
  std::map<std::string, std::unique_ptr<WarpBackend>> backends_;
};

}  // namespace texwarp::runner
