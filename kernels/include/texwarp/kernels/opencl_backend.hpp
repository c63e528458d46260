// The OpenCL compute path, as the rest of texwarp sees it: device choice, the backend factory and the list of
// devices (for `texwarp --list-devices`). The backend class itself is in opencl_warp_backend.hpp.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "texwarp/core/warp_backend.hpp"

namespace texwarp {

// Arithmetic of the pathline kernel: kAuto runs float32 for tolerances ≥ kFloatMinTolerancePx and double below
// (opencl_warp_backend.hpp); the others force one (kDouble needs cl_khr_fp64).
enum class OpenClPrecision { kAuto, kFloat, kDouble };

// Which OpenCL device runs the warp, and how. Name matching is case-insensitive.
struct OpenClOptions {
  // A substring of the platform name ("pocl", "NVIDIA"); empty: any platform.
  std::string platform;
  // A substring of the device name, or a device type: "cpu", "gpu", "accelerator", "all" (any type).
  // Empty: PoCL's CPU device when present, else the first CPU device, else the first device.
  std::string device;
  OpenClPrecision precision = OpenClPrecision::kAuto;
};

// The OpenCL backend on the chosen device; its program is built on first use (once per process and device).
// Throws OpenClError with an actionable message when there is no OpenCL platform or no device matches.
std::unique_ptr<WarpBackend> make_opencl_backend(const OpenClOptions& options = {});

// One line per device of every platform: "platform P device D: <device name> (<type>, <platform name>,
// <version>, <compute units> compute units)", with " [default]" on the one empty OpenClOptions select.
// Empty when there is no OpenCL platform.
std::vector<std::string> list_opencl_devices();

}  // namespace texwarp
