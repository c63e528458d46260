// BackendCache: the compute backends one worker uses, made on first use and kept (an OpenCL backend holds a
// context, a queue and built programs): "cpu" is the double-precision reference, "opencl[:<device>]" the
// kernels. One cache per worker thread: backends are not shared between threads.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "texwarp/core/warp_backend.hpp"

namespace texwarp::runner {

// "opencl": jobs that name no device run on the OpenCL backend (PoCL on the CPU unless a device is named).
const char* default_device();

// InputError at `where` unless `device` is "", "cpu", "opencl" or "opencl:<name>".
void check_device(const std::string& device, const std::string& where);

class BackendCache {
 public:
  // `default_device` answers jobs that name none ("" here means default_device()).
  explicit BackendCache(std::string default_device = "");

  // The backend for `device` ("" for the default). InputError at `where` for a device that is none of those or
  // an OpenCL device name that matches no device; the OpenCL backend's own error when the device cannot be opened.
  WarpBackend& get(const std::string& device, const std::string& where = "$.options.device");

  const std::string& default_name() const { return default_; }

 private:
  std::string default_;
  std::map<std::string, std::unique_ptr<WarpBackend>> backends_;
};

}  // namespace texwarp::runner
