// BackendCache: the compute backends one worker uses, made on first use and kept (an OpenCL backend holds a
// context, a queue and built programs): "cpu" is the double-precision reference, "opencl[:<device>]" the
// kernels when this build has them. One cache per worker thread: backends are not shared between threads.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>

#include "texwarp/core/warp_backend.hpp"
#include "texwarp/proto/device_spec.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp::runner {

// True when this build has the OpenCL backend (texwarp_kernels).
bool has_opencl();

// "opencl" when built with OpenCL, else "cpu".
const char* default_device();

// InputError at `where` unless this build can run `device`.
void check_device(const proto::DeviceSpec& device, const proto::InputLocation& where);

class BackendCache {
 public:
  // `default_device` answers jobs that name none (none here means default_device()); InputError when this build
  // cannot run it.
  explicit BackendCache(std::optional<proto::DeviceSpec> default_device = std::nullopt);

  // The backend for `device` (none: the default). InputError at `where` for a device this build cannot run or
  // an OpenCL device name that matches no device; the OpenCL backend's own error when the device cannot be opened.
  WarpBackend& get(const std::optional<proto::DeviceSpec>& device,
                   const proto::InputLocation& where = proto::JsonPath{"options", "device"});

  std::string default_name() const { return default_.str(); }

 private:
  proto::DeviceSpec default_;
  std::map<std::string, std::unique_ptr<WarpBackend>> backends_;  // by DeviceSpec::str()
};

}  // namespace texwarp::runner
