// The on-disk cache of built OpenCL programs (private): program binaries keyed by device name, driver version,
// build options and a hash of the source, one file each under <cache folder>/programs; written atomically, read
// back only when the whole key inside the file matches, so a corrupt or foreign file is ignored and rebuilt.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace texwarp::kernels_detail {

struct ProgramKey {
  std::string device;  // CL_DEVICE_NAME
  std::string driver;  // CL_DRIVER_VERSION and the platform's CL_PLATFORM_VERSION
  std::string options;
  std::string source;
};

// <cache folder>/programs/<64-bit FNV-1a of the key, hex>.bin; empty when no cache folder can be made.
std::filesystem::path program_cache_file(const ProgramKey& key);

// The cached binary for `key`: none when absent, unreadable, truncated or made for another key.
std::optional<std::vector<unsigned char>> load_program_binary(const ProgramKey& key);

// Stores `binary` for `key` (atomically: a reader sees the old file or the whole new one). A cache that cannot be
// written is skipped silently: the next process builds from source again.
void store_program_binary(const ProgramKey& key, const std::vector<unsigned char>& binary);

}  // namespace texwarp::kernels_detail
