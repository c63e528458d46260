// OpenCL devices for the kernels library (private): enumeration and selection by OpenClOptions, one context per
// device and the per-process table of built programs (kept as program binaries between processes),
// POCL_CACHE_DIR set before the first OpenCL call. Safe from
// any thread: enumeration, context creation and builds run under one process-wide lock (PoCL's start-up is not).
#pragma once

#include <CL/opencl.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "texwarp/kernels/opencl_backend.hpp"

namespace texwarp::kernels_detail {

// A selected device with the process-wide context that its programs are built in.
struct DeviceHandle {
  cl::Device device;
  cl::Context context;
  std::string device_name;
  std::string platform_name;
  bool has_fp64 = false;
  unsigned compute_units = 1;
  std::size_t max_alloc_bytes = 0;
};

// texwarp's cache folder (set_opencl_cache_dir, else $TEXWARP_CACHE_DIR, else $XDG_CACHE_HOME/texwarp, else
// $HOME/.cache/texwarp, else <temp>/texwarp-cache-<uid>: the first that can be created); empty when none can.
// Decided once per process, on first use.
std::filesystem::path cache_dir();

// Sets POCL_CACHE_DIR to <cache_dir()>/pocl when the environment has none. Runs once per process; every entry
// point calls it before any OpenCL call.
void ensure_pocl_cache_dir();

// Throws OpenClError naming the options and the devices available when nothing matches.
DeviceHandle select_device(const OpenClOptions& options);

// See list_opencl_devices() in opencl_backend.hpp.
std::vector<std::string> describe_devices();

// `source` built for the device with these options (-cl-std=CL1.2 and -w are added: no compiler warnings on
// stderr), once per process, device, source and options. Between processes the program can be kept as the
// driver's program binary in program_binary_folder() (program_binary_cache.hpp): a new process builds it from
// that binary when the file's key (options, source, platform, device and driver versions) is this build's and the
// file is whole, and otherwise from source, then (re)writes the file if keep_opencl_program_binaries asked for it;
// a cache that fails only costs the source build.
// The driver's own cache holds what it compiled (PoCL: the program's bitcode at build, each launch shape's
// machine code at its first launch, in POCL_CACHE_DIR). Throws OpenClError carrying the build log when the build
// from source fails.
cl::Program build_program(const DeviceHandle& device, const std::string& source, const std::string& options);

// Where build_program keeps program binaries: <cache_dir()>/programs; empty (none kept) when cache_dir() is.
std::filesystem::path program_binary_folder();

// Tests: build_program forgets the programs this process built (its next build is a new process's) and keeps
// program binaries in `binary_folder` (empty: none; nullopt: program_binary_folder's own) from now on.
void forget_programs_for_tests(const std::optional<std::filesystem::path>& binary_folder);

// The driver's compile cache: POCL_CACHE_DIR (ensure_pocl_cache_dir() first); empty when it has none.
std::filesystem::path driver_cache_dir();

// Compiled files in driver_cache_dir() now: PoCL's program bitcode (program.bc) and machine code (*.so, one per
// kernel and launch shape). A count that does not change across a run means the run compiled nothing.
std::size_t driver_cache_files();

}  // namespace texwarp::kernels_detail
