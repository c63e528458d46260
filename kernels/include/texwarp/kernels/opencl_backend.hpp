// The OpenCL compute path, as the rest of texwarp sees it: device choice, the backend factory and the list of
// devices (for `texwarp --list-devices`). The backend class itself is in opencl_warp_backend.hpp.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "texwarp/core/warp_backend.hpp"

namespace texwarp {

// Arithmetic of the pathline kernel: kAuto runs float32 for tolerances ≥ kFloatMinTolerancePx and double below,
// and runs a call again in double where float32's steps collapsed (opencl_warp_backend.hpp); the others force one
// (kDouble needs cl_khr_fp64).
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

// The cache folder, where compiled kernels are kept between processes: `folder` from now on. The driver's compile
// cache goes in its pocl/ unless POCL_CACHE_DIR is set (PoCL: each program's bitcode and, per launch shape, its
// machine code), the built programs in its programs/ (keep_opencl_program_binaries). Must come before the first OpenCL
// call (texwarpd's --cache-dir); otherwise $TEXWARP_CACHE_DIR, else $XDG_CACHE_HOME/texwarp, else $HOME/.cache/texwarp,
// else <temp>/texwarp-cache-<uid>, created on first use. Once the folder is in use it stays for the process: false then
// (several servers in one test process share the first one's).
bool set_opencl_cache_dir(const std::string& folder);

// Whether the programs this process builds from source are also written to the cache folder's programs/ as the
// driver's program binaries, which later processes build from instead of the source (PoCL 3.1: about 17 ms a
// program instead of 65 ms; every process reads them, whoever wrote them). Off until asked: to write a binary
// PoCL compiles each kernel once more, for any work-group size, about as long as the program's first build
// (`texwarp warm` on a fresh folder here: 10–12 s without binaries, 17–23 s with), which `texwarp warm` pays for
// the processes after it and a first warp or texwarpd's start should not.
void keep_opencl_program_binaries(bool keep = true);

// The cache folder in use (deciding it if not yet decided); empty when none could be created.
std::string opencl_cache_dir();

// Where the driver keeps what it compiles: POCL_CACHE_DIR (<cache folder>/pocl unless the user set it).
std::string opencl_driver_cache_dir();

// What this process's OpenCL side did so far: contexts opened (one per device), programs built (from source, the
// driver compiling them or finding them in its cache, or from a program binary in the cache folder's programs/),
// of those the ones built from a program binary, and the compiled files now in the driver's cache (PoCL: bitcode
// and machine code; 0 for a driver that keeps none there). Files that a run adds are compiles it paid for.
struct OpenClActivity {
  std::size_t contexts = 0;
  std::size_t programs_built = 0;
  std::size_t programs_from_binary = 0;
  std::size_t driver_cache_files = 0;
};
OpenClActivity opencl_activity();

// What warm_opencl_programs did: the kernel variants it ran, and the compiled files it added to the driver's
// cache (0 when everything was there already).
struct OpenClWarmth {
  std::size_t variants = 0;
  std::size_t files_compiled = 0;
};

// Builds every kernel variant that jobs use on the chosen device (float and double arithmetic, with and without
// the Jacobian; the precision option limits them) and launches each once on a tiny problem in the launch shape
// real runs use, so that the driver has compiled and cached all of it: after this a first warp in a new process
// compiles nothing. texwarpd before /readyz says ready,
// `texwarp warm` for the quick start. OpenClError as make_opencl_backend.
OpenClWarmth warm_opencl_programs(const OpenClOptions& options = {});

// One line per device of every platform: "platform P device D: <device name> (<type>, <platform name>,
// <version>, <compute units> compute units)", with " [default]" on the one empty OpenClOptions select.
// Empty when there is no OpenCL platform.
std::vector<std::string> list_opencl_devices();

}  // namespace texwarp
