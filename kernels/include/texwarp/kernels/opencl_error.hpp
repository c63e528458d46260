// OpenClError: the OpenCL compute path cannot run: no platform or no matching device (OpenClNoMatchingDevice),
// a program that does not build (the build log is in the message), or an OpenCL call that failed (its name and
// error code).
#pragma once

#include <stdexcept>
#include <string>

namespace texwarp {

class OpenClError : public std::runtime_error {
 public:
  explicit OpenClError(const std::string& what) : std::runtime_error(what) {}
};

// No device matches the platform/device the caller named: the caller's mistake, not the machine's (the message
// lists the devices there are).
class OpenClNoMatchingDevice : public OpenClError {
 public:
  using OpenClError::OpenClError;
};

}  // namespace texwarp
