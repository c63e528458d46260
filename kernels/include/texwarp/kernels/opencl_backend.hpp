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

// The folder where compiled kernels are kept between processes (program binaries under programs/, PoCL's own
// cache under pocl/ unless POCL_CACHE_DIR is set): `folder` from now on. Must come before the first OpenCL call
// (texwarpd's --cache-dir); otherwise $TEXWARP_CACHE_DIR, else $XDG_CACHE_HOME/texwarp, else $HOME/.cache/texwarp,
// else <temp>/texwarp-cache-<uid>, created on first use. Once the folder is in use it stays for the process: false
// then (several servers in one test process share the first one's).
bool set_opencl_cache_dir(const std::string& folder);

// The cache folder in use (deciding it if not yet decided); empty when none could be created.
std::string opencl_cache_dir();

// What this process's OpenCL side did so far: contexts opened (one per device), programs compiled from source,
// programs loaded from the cache's binaries, cache files found unusable (rebuilt from source).
struct OpenClActivity {
  std::size_t contexts = 0;
  std::size_t programs_compiled = 0;
  std::size_t programs_from_cache = 0;
  std::size_t cache_entries_rejected = 0;
};
OpenClActivity opencl_activity();

// Builds every kernel variant for the chosen device now (the program cache's binaries, or from source and then
// into the cache): texwarpd before /readyz says ready, `texwarp warm` for the quick start. OpenClError as
// make_opencl_backend.
void warm_opencl_programs(const OpenClOptions& options = {});

// One line per device of every platform: "platform P device D: <device name> (<type>, <platform name>,
// <version>, <compute units> compute units)", with " [default]" on the one empty OpenClOptions select.
// Empty when there is no OpenCL platform.
std::vector<std::string> list_opencl_devices();

}  // namespace texwarp
