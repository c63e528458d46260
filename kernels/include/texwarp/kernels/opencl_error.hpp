// OpenClError: the OpenCL compute path cannot run: no platform or no matching device, a program that does not
// build (the build log is in the message), or an OpenCL call that failed (its name and error code).
#pragma once

#include <stdexcept>
#include <string>

namespace texwarp {

class OpenClError : public std::runtime_error {
 public:
  explicit OpenClError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace texwarp
