// Built OpenCL programs kept between processes as the driver's program binaries (CL_PROGRAM_BINARIES), one file
// per program in a folder (build_program's <cache_dir()>/programs): a new process creates its program from the
// binary instead of building it from source (PoCL: ~17 ms instead of ~65 ms, its front end not run). A file
// holds the whole key that it was built for and a checksum of the binary; anything that does not match exactly
// (or is not a regular file of this user's, or is larger than any binary of ours) is ignored. What matches is
// handed to the driver, which trusts it (PoCL asserts on a malformed binary): the folder is the user's own, as the
// driver's machine-code cache beside it is. Nothing here throws: a cache that fails is a cache that misses.
#pragma once

#include <CL/opencl.hpp>

#include <filesystem>
#include <optional>
#include <string>

#include "opencl_device.hpp"

namespace texwarp::kernels_detail {

// What a program binary depends on: the build options, the source, the platform's and device's names and
// versions, the driver's version, the driver's libraries as they are on disk (path, size, time, inode: a package
// update changes them where the version strings stay) and the driver settings that change its code
// (POCL_WORK_GROUP_METHOD, POCL_EXTRA_BUILD_FLAGS). The source carries texwarp's kernel contract
// (kernel_prelude). Empty when the device does not say them: no binary is kept then.
std::string program_binary_key(const DeviceHandle& device, const std::string& source, const std::string& build_options);

// The file in `folder` that holds the program for `key` (named by a hash of the key).
std::filesystem::path program_binary_file(const std::filesystem::path& folder, const std::string& key);

// The program for `key` created from the binary in `folder` and built with `build_options`; nullopt when there is
// no file, it is not whole, its key is not `key`, or the driver refuses the binary or fails to build it.
std::optional<cl::Program> load_program_binary(const DeviceHandle& device, const std::filesystem::path& folder,
                                               const std::string& key, const std::string& build_options);

// Writes `program`'s binary (built for the device) for `key` in `folder`, created if missing: to a temporary
// file that is then renamed, so a reader (another process) sees the old file, the whole new one or none. False
// when it cannot (a folder it cannot write in, checked before the driver is asked for the binary; no binary; a
// write error).
bool store_program_binary(const DeviceHandle& device, const std::filesystem::path& folder, const std::string& key,
                          const cl::Program& program);

}  // namespace texwarp::kernels_detail
