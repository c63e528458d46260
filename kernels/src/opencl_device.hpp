// OpenCL devices for the kernels library (private): enumeration and selection by OpenClOptions, one context per
// device and the per-process cache of built programs, POCL_CACHE_DIR set before the first OpenCL call. Safe from
// any thread: enumeration, context creation and builds run under one process-wide lock (PoCL's start-up is not).
#pragma once

#include <CL/opencl.hpp>

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

// Sets POCL_CACHE_DIR when the environment has none: $XDG_CACHE_HOME/texwarp/pocl, else
// $HOME/.cache/texwarp/pocl, else <temp>/texwarp-pocl-cache-<uid> (the first of them that can be created).
// Runs once per process; every entry point calls it before any OpenCL call.
void ensure_pocl_cache_dir();

// Throws OpenClError naming the options and the devices available when nothing matches.
DeviceHandle select_device(const OpenClOptions& options);

// See list_opencl_devices() in opencl_backend.hpp.
std::vector<std::string> describe_devices();

// `source` built for the device with these options (-cl-std=CL1.2 and -w are added: no compiler warnings on
// stderr), once per process, device, source and options. Throws OpenClError carrying the build log on failure.
cl::Program build_program(const DeviceHandle& device, const std::string& source, const std::string& options);

}  // namespace texwarp::kernels_detail
