// BackendCache: the compute backends one worker uses, made on first use and kept (an OpenCL backend holds a
// context, a queue and built programs): "cpu" is the double-precision reference, "opencl[:<device>]" the
// kernels. One cache per worker thread: backends are not shared between threads.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>

#include "texwarp/core/warp_backend.hpp"
#include "texwarp/proto/device_spec.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp::runner {

// "opencl": jobs that name no device run on the OpenCL backend (PoCL on the CPU unless a device is named).
const char* default_device();

// Where compiled kernels are kept between processes (set before any device is opened; see set_opencl_cache_dir).
void use_kernel_cache_dir(const std::string& folder);

// Builds and launches every kernel variant of `device` now, so that the driver has compiled and cached them
// (texwarpd before /readyz says ready); nothing for the CPU backend. What happened, for a log line: "4 variants
// launched, 0 files compiled into <driver cache>". The OpenCL backend's errors as get()'s.
std::string warm_kernels(const proto::DeviceSpec& device);

class BackendCache {
 public:
  // `default_device` answers jobs that name none (none here means default_device()).
  explicit BackendCache(std::optional<proto::DeviceSpec> default_device = std::nullopt);

  // The backend for `device` (none: the default). InputError at `where` for an OpenCL device name that matches
  // no device; the OpenCL backend's own error when the device cannot be opened.
  WarpBackend& get(const std::optional<proto::DeviceSpec>& device,
                   const proto::InputLocation& where = proto::JsonPath{"options", "device"});

  std::string default_name() const { return default_.str(); }

 private:
  proto::DeviceSpec default_;
  std::map<std::string, std::unique_ptr<WarpBackend>> backends_;  // by DeviceSpec::str()
};

}  // namespace texwarp::runner
