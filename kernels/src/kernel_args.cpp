// Comparing a kernel's parameter list with the host's: see kernel_args.hpp.
#include "kernel_args.hpp"

namespace texwarp::kernels_detail {

std::string parameter_mismatch(std::span<const std::string_view> names, std::span<const bool> buffers,
                               const KernelParameters& actual) {
  if (actual.count != names.size()) {
    return "it has " + std::to_string(actual.count) + " parameters, the host binds " + std::to_string(names.size());
  }
  if (actual.names.empty()) return {};
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (actual.names[i] != names[i]) {
      return "parameter " + std::to_string(i) + " is \"" + actual.names[i] + "\", the host binds \"" +
             std::string(names[i]) + "\" there";
    }
    if (i < actual.global.size() && actual.global[i] != buffers[i]) {
      return "parameter " + std::to_string(i) + " (\"" + actual.names[i] + "\") is " +
             (actual.global[i] ? "a __global pointer" : "a value") + ", the host binds " +
             (buffers[i] ? "a buffer" : "a value");
    }
  }
  return {};
}

}  // namespace texwarp::kernels_detail
