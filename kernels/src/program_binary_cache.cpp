// Program binaries kept between processes, checked whole before the driver sees them: see program_binary_cache.hpp.
#include "program_binary_cache.hpp"

#include <link.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string_view>
#include <vector>

#include "texwarp/core/text_file.hpp"

namespace texwarp::kernels_detail {
namespace {

// A file: this line, then "<key bytes> <binary bytes> <FNV-1a of the binary>" as 16 hex digits each and a
// newline, then the key, then the binary, and nothing more.
constexpr std::string_view kMagic = "texwarp-program-binary 1\n";
constexpr std::size_t kSizesLength = std::size_t{3} * 17;
// Larger is not a program binary of ours (PoCL's pathline binaries: 0.4–0.6 MB); not even read.
constexpr long long kMaxFileBytes = 16LL << 20;

// What the driver's libraries are on disk: path, size, modification time and inode of every loaded shared object
// named like an OpenCL driver or its compiler (PoCL, LLVM, clang, an ICD's libOpenCL, a vendor's *opencl*). A
// package update replaces them, and with them what a binary links (PoCL's kernel library): the platform and driver
// version strings stay the same across Debian revisions, so they alone would keep a stale binary.
std::string driver_libraries() {
  std::vector<std::string> found;
  dl_iterate_phdr(
      [](dl_phdr_info* info, std::size_t, void* out) {
        const std::string path = info->dlpi_name == nullptr ? std::string() : std::string(info->dlpi_name);
        std::string name = path.substr(path.find_last_of('/') == std::string::npos ? 0 : path.find_last_of('/') + 1);
        std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
        const bool driver = name.find("pocl") != std::string::npos || name.find("opencl") != std::string::npos ||
                            name.find("llvm") != std::string::npos || name.find("clang") != std::string::npos;
        struct stat st {};
        if (driver && ::stat(path.c_str(), &st) == 0) {
          static_cast<std::vector<std::string>*>(out)->push_back(
              path + ' ' + std::to_string(st.st_size) + ' ' + std::to_string(st.st_mtim.tv_sec) + '.' +
              std::to_string(st.st_mtim.tv_nsec) + ' ' + std::to_string(st.st_ino));
        }
        return 0;
      },
      &found);
  std::sort(found.begin(), found.end());
  std::string out;
  for (const std::string& f : found) out += f + '\n';
  return out;
}

// The driver's settings that change what it compiles (PoCL's work-group method, its extra build flags).
std::string driver_settings() {
  std::string out;
  for (const char* name : {"POCL_WORK_GROUP_METHOD", "POCL_EXTRA_BUILD_FLAGS"}) {
    const char* value = std::getenv(name);
    out += std::string(name) + '=' + (value == nullptr ? "" : value) + '\n';
  }
  return out;
}

std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t hash = 14695981039346656037ULL;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ULL;
  }
  return hash;
}

std::string hex16(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

// The three sizes' line, parsed only when it is exactly what hex16 writes.
bool parse_sizes(std::string_view line, std::uint64_t (&values)[3]) {
  if (line.size() != kSizesLength) return false;
  for (std::size_t v = 0; v < 3; ++v) {
    values[v] = 0;
    for (std::size_t i = 0; i < 16; ++i) {
      const char c = line[v * 17 + i];
      const int digit = c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
      if (digit < 0) return false;
      values[v] = values[v] * 16 + static_cast<std::uint64_t>(digit);
    }
    if (line[v * 17 + 16] != (v == 2 ? '\n' : ' ')) return false;
  }
  return true;
}

// The binary stored for `key` in `file`, when the file is whole and its key is `key`.
std::optional<std::string> read_binary(const std::filesystem::path& file, const std::string& key) {
  // A regular file of this user's (not a link, not another user's), no larger than a binary of ours can be.
  struct stat st {};
  if (::lstat(file.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != ::geteuid() ||
      st.st_size > kMaxFileBytes) {
    return std::nullopt;
  }
  const std::string text = read_text_file(file.string(), kMaxFileBytes);
  const std::string_view all(text);
  std::uint64_t sizes[3];
  if (!all.starts_with(kMagic) || !parse_sizes(all.substr(kMagic.size(), kSizesLength), sizes)) return std::nullopt;
  const std::string_view rest = all.substr(std::min(all.size(), kMagic.size() + kSizesLength));
  const auto [key_bytes, binary_bytes, checksum] = sizes;
  if (key_bytes != key.size() || binary_bytes == 0 || rest.size() != key_bytes + binary_bytes) return std::nullopt;
  if (rest.substr(0, key_bytes) != key) return std::nullopt;
  const std::string_view binary = rest.substr(key_bytes);
  if (fnv1a(binary) != checksum) return std::nullopt;
  return std::string(binary);
}

}  // namespace

std::string program_binary_key(const DeviceHandle& device, const std::string& source,
                               const std::string& build_options) {
  std::string key = "options " + build_options + '\0';
  try {
    const cl::Platform platform(device.device.getInfo<CL_DEVICE_PLATFORM>());
    for (const std::string& part : {platform.getInfo<CL_PLATFORM_NAME>(), platform.getInfo<CL_PLATFORM_VERSION>(),
                                    device.device.getInfo<CL_DEVICE_NAME>(), device.device.getInfo<CL_DEVICE_VERSION>(),
                                    device.device.getInfo<CL_DRIVER_VERSION>()}) {
      key += part.substr(0, part.find('\0'));  // without the trailing NUL some drivers include
      key += '\0';
    }
    key += driver_libraries() + driver_settings();
  } catch (const cl::Error&) {  // a device that does not say what it is keeps no binaries
    return {};
  }
  return key + "source\n" + source;
}

std::filesystem::path program_binary_file(const std::filesystem::path& folder, const std::string& key) {
  return folder / (hex16(std::hash<std::string>{}(key)) + ".clbin");
}

std::optional<cl::Program> load_program_binary(const DeviceHandle& device, const std::filesystem::path& folder,
                                               const std::string& key, const std::string& build_options) {
  try {
    const std::optional<std::string> binary = read_binary(program_binary_file(folder, key), key);
    if (!binary) return std::nullopt;
    const cl::Program::Binaries binaries{std::vector<unsigned char>(binary->begin(), binary->end())};
    std::vector<cl_int> status;
    cl::Program program(device.context, std::vector<cl::Device>{device.device}, binaries, &status);
    if (status.size() != 1 || status[0] != CL_SUCCESS) return std::nullopt;
    program.build(std::vector<cl::Device>{device.device}, build_options.c_str());
    return program;
  } catch (...) {  // an unreadable file, CL_INVALID_BINARY, a failed build: the caller builds from source
    return std::nullopt;
  }
}

bool store_program_binary(const DeviceHandle& device, const std::filesystem::path& folder, const std::string& key,
                          const cl::Program& program) {
  try {
    // Before asking for the binary, which makes PoCL compile every kernel once more: a folder this process cannot
    // write in is not worth it.
    std::filesystem::create_directories(folder);
    if (::access(folder.c_str(), W_OK) != 0) return false;
    const std::vector<cl::Device> devices = program.getInfo<CL_PROGRAM_DEVICES>();
    const cl::Program::Binaries binaries = program.getInfo<CL_PROGRAM_BINARIES>();
    if (devices.size() != 1 || binaries.size() != 1 || devices[0]() != device.device() || binaries[0].empty()) {
      return false;
    }
    const std::string_view binary(reinterpret_cast<const char*>(binaries[0].data()), binaries[0].size());
    std::string text(kMagic);
    text += hex16(key.size()) + ' ' + hex16(binary.size()) + ' ' + hex16(fnv1a(binary)) + '\n';
    text += key;
    text += binary;
    write_text_file_atomically(program_binary_file(folder, key).string(), text);
    return true;
  } catch (...) {  // no folder, a full disk, a driver without binaries: the next process builds from source
    return false;
  }
}

}  // namespace texwarp::kernels_detail
