// Device enumeration and selection, the per-device context and program cache: see opencl_device.hpp.
#include "opencl_device.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <utility>

#include "opencl_calls.hpp"
#include "program_binary_cache.hpp"
#include "texwarp/kernels/opencl_error.hpp"

namespace texwarp::kernels_detail {
namespace {

constexpr std::string_view kEnumerationFailed = "OpenCL device enumeration failed";

// PoCL 3.1 and ocl-icd initialise themselves on the first OpenCL call without a lock: two threads enumerating
// platforms at once crash or see no platform. Enumeration, context creation and program builds hold this lock.
std::recursive_mutex& runtime_mutex() {
  static std::recursive_mutex mutex;
  return mutex;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool contains(const std::string& text, const std::string& part) {
  return lower(text).find(lower(part)) != std::string::npos;
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\0' || std::isspace(static_cast<unsigned char>(s.back())))) s.pop_back();
  return s;
}

const char* type_name(cl_device_type type) {
  if (type & CL_DEVICE_TYPE_GPU) return "gpu";
  if (type & CL_DEVICE_TYPE_CPU) return "cpu";
  if (type & CL_DEVICE_TYPE_ACCELERATOR) return "accelerator";
  return "other";
}

bool is_pocl(const cl::Platform& platform) {
  return contains(platform.getInfo<CL_PLATFORM_NAME>(), "portable computing language") ||
         contains(platform.getInfo<CL_PLATFORM_VENDOR>(), "pocl");
}

struct Candidate {
  std::size_t platform_index;
  std::size_t device_index;
  cl::Platform platform;
  cl::Device device;
};

// Every device of every platform, in platform order; empty when there is no platform.
std::vector<Candidate> enumerate() {
  ensure_pocl_cache_dir();
  std::lock_guard lock(runtime_mutex());
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error& e) {
    if (e.err() == kPlatformNotFound) return {};
    throw;
  }
  std::vector<Candidate> all;
  for (std::size_t p = 0; p < platforms.size(); ++p) {
    std::vector<cl::Device> devices;
    try {
      platforms[p].getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error& e) {
      if (e.err() == CL_DEVICE_NOT_FOUND) continue;
      throw;
    }
    for (std::size_t d = 0; d < devices.size(); ++d) all.push_back({p, d, platforms[p], devices[d]});
  }
  return all;
}

// The device empty options select: PoCL's CPU device, else the first CPU device, else the first device.
std::size_t default_index(const std::vector<Candidate>& all) {
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (is_pocl(all[i].platform) && (all[i].device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU)) return i;
  }
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU) return i;
  }
  return 0;
}

std::string describe(const Candidate& c) {
  const cl::Device& d = c.device;
  return "platform " + std::to_string(c.platform_index) + " device " + std::to_string(c.device_index) + ": " +
         trim(d.getInfo<CL_DEVICE_NAME>()) + " (" + type_name(d.getInfo<CL_DEVICE_TYPE>()) + ", " +
         trim(c.platform.getInfo<CL_PLATFORM_NAME>()) + ", " + trim(d.getInfo<CL_DEVICE_VERSION>()) + ", " +
         std::to_string(d.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>()) + " compute units)";
}

bool matches_device(const cl::Device& device, const std::string& wanted) {
  if (wanted.empty() || lower(wanted) == "all") return true;
  const cl_device_type type = device.getInfo<CL_DEVICE_TYPE>();
  const std::string w = lower(wanted);
  if (w == "cpu") return (type & CL_DEVICE_TYPE_CPU) != 0;
  if (w == "gpu") return (type & CL_DEVICE_TYPE_GPU) != 0;
  if (w == "accelerator") return (type & CL_DEVICE_TYPE_ACCELERATOR) != 0;
  return contains(trim(device.getInfo<CL_DEVICE_NAME>()), wanted);
}

// One context per device for the whole process, and the programs built in it.
struct DeviceEntry {
  cl::Context context;
  std::map<std::string, cl::Program> programs;  // by build options, then source
};

std::map<cl_device_id, DeviceEntry>& registry() {
  static std::map<cl_device_id, DeviceEntry> entries;
  return entries;
}

// Where build_program keeps program binaries when a test chose (forget_programs_for_tests); else
// <cache_dir()>/programs. Under runtime_mutex.
std::optional<std::filesystem::path>& binary_folder_for_tests() {
  static std::optional<std::filesystem::path> folder;
  return folder;
}

// keep_opencl_program_binaries: build_program writes the binaries of the programs it builds from source.
std::atomic<bool>& keeping_binaries() {
  static std::atomic<bool> keep{false};
  return keep;
}

struct Counters {
  std::atomic<std::size_t> contexts{0};
  std::atomic<std::size_t> built{0};
  std::atomic<std::size_t> loaded{0};
};

Counters& counters() {
  static Counters c;
  return c;
}

// The cache folder: asked for (set_opencl_cache_dir) before it is decided, then fixed for the process.
struct CacheFolder {
  std::mutex mutex;
  std::optional<std::filesystem::path> chosen;  // decided
  std::filesystem::path requested;
};

CacheFolder& cache_folder() {
  static CacheFolder c;
  return c;
}

bool usable_folder(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  return !ec && ::access(dir.c_str(), W_OK) == 0;
}

// A folder in a place every user can write (the temporary folder): usable only when it is a real folder of this
// user's, then kept to this user alone (0700). The driver loads machine code from the cache (PoCL's .so files) and
// texwarp its program binaries: another user who created /tmp/texwarp-cache-<uid> first must not place them.
bool private_folder(const std::filesystem::path& dir) {
  if (!usable_folder(dir)) return false;
  struct stat st {};
  return ::lstat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode) && st.st_uid == ::geteuid() &&
         ((st.st_mode & 0777) == 0700 || ::chmod(dir.c_str(), 0700) == 0);
}

std::string getenv_or_empty(const char* name) {
  const char* value = std::getenv(name);
  return value == nullptr ? std::string() : std::string(value);
}

}  // namespace

std::filesystem::path cache_dir() {
  namespace fs = std::filesystem;
  CacheFolder& c = cache_folder();
  std::lock_guard lock(c.mutex);
  if (c.chosen) return *c.chosen;
  std::vector<fs::path> choices;
  fs::path shared_temp;  // the last choice, in the temporary folder
  if (!c.requested.empty()) {
    choices.push_back(c.requested);
  } else {
    if (const std::string own = getenv_or_empty("TEXWARP_CACHE_DIR"); !own.empty()) choices.emplace_back(own);
    if (const std::string xdg = getenv_or_empty("XDG_CACHE_HOME"); !xdg.empty()) {
      choices.push_back(fs::path(xdg) / "texwarp");
    }
    if (const std::string home = getenv_or_empty("HOME"); !home.empty()) {
      choices.push_back(fs::path(home) / ".cache" / "texwarp");
    }
    std::error_code ec;
    fs::path temp = fs::temp_directory_path(ec);
    if (ec) temp = "/tmp";
    shared_temp = temp / ("texwarp-cache-" + std::to_string(::getuid()));
    choices.push_back(shared_temp);
  }
  c.chosen = fs::path();
  for (const fs::path& dir : choices) {
    if (dir == shared_temp ? private_folder(dir) : usable_folder(dir)) {
      c.chosen = dir;
      break;
    }
  }
  return *c.chosen;
}

void ensure_pocl_cache_dir() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!getenv_or_empty("POCL_CACHE_DIR").empty()) return;
    const std::filesystem::path dir = cache_dir();
    if (!dir.empty() && usable_folder(dir / "pocl")) ::setenv("POCL_CACHE_DIR", (dir / "pocl").c_str(), 0);
  });
}

DeviceHandle select_device(const OpenClOptions& options) {
  std::lock_guard runtime_lock(runtime_mutex());
  const std::vector<Candidate> all = with_cl_errors(kEnumerationFailed, enumerate);
  if (all.empty()) {
    throw OpenClError(
        "no OpenCL platform found: install an OpenCL driver (on Debian: apt install pocl-opencl-icd) or use the "
        "CPU backend");
  }
  std::vector<std::size_t> matching;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const bool platform_ok =
        options.platform.empty() || contains(all[i].platform.getInfo<CL_PLATFORM_NAME>(), options.platform);
    if (platform_ok && matches_device(all[i].device, options.device)) matching.push_back(i);
  }
  if (matching.empty()) {
    std::string msg = "no OpenCL device matches";
    if (!options.platform.empty()) msg += " platform \"" + options.platform + "\"";
    if (!options.device.empty()) msg += " device \"" + options.device + "\"";
    msg += " (a device is chosen by a substring of its name or by cpu, gpu, accelerator, all); available:";
    for (const Candidate& c : all) msg += "\n  " + describe(c);
    throw OpenClNoMatchingDevice(msg);
  }
  std::size_t chosen = matching.front();
  if (options.platform.empty() && options.device.empty()) chosen = default_index(all);

  const Candidate& c = all[chosen];
  DeviceHandle handle;
  handle.device = c.device;
  handle.device_name = trim(c.device.getInfo<CL_DEVICE_NAME>());
  handle.platform_name = trim(c.platform.getInfo<CL_PLATFORM_NAME>());
  handle.has_fp64 = c.device.getInfo<CL_DEVICE_EXTENSIONS>().find("cl_khr_fp64") != std::string::npos;
  handle.compute_units = std::max<cl_uint>(1, c.device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>());
  handle.max_alloc_bytes = static_cast<std::size_t>(c.device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>());
  handle.context = with_cl_errors("cannot create an OpenCL context on " + handle.device_name, [&] {
    auto it = registry().find(c.device());
    if (it == registry().end()) {
      it = registry().emplace(c.device(), DeviceEntry{cl::Context(c.device), {}}).first;
      ++counters().contexts;
    }
    return it->second.context;
  });
  return handle;
}

std::vector<std::string> describe_devices() {
  std::lock_guard runtime_lock(runtime_mutex());
  const std::vector<Candidate> all = with_cl_errors(kEnumerationFailed, enumerate);
  std::vector<std::string> lines;
  const std::size_t chosen = all.empty() ? 0 : default_index(all);
  for (std::size_t i = 0; i < all.size(); ++i) lines.push_back(describe(all[i]) + (i == chosen ? " [default]" : ""));
  return lines;
}

std::filesystem::path program_binary_folder() {
  std::lock_guard lock(runtime_mutex());
  if (binary_folder_for_tests()) return *binary_folder_for_tests();
  const std::filesystem::path dir = cache_dir();
  return dir.empty() ? dir : dir / "programs";
}

void forget_programs_for_tests(const std::optional<std::filesystem::path>& binary_folder) {
  std::lock_guard lock(runtime_mutex());
  for (auto& [id, entry] : registry()) entry.programs.clear();
  binary_folder_for_tests() = binary_folder;
}

cl::Program build_program(const DeviceHandle& device, const std::string& source, const std::string& options) {
  std::lock_guard lock(runtime_mutex());
  DeviceEntry& entry = registry().at(device.device());
  const std::string table_key = options + '\0' + source;
  if (auto it = entry.programs.find(table_key); it != entry.programs.end()) return it->second;
  // -w: the compiler's warnings stay out of the build log (PoCL prints them); a failed build's log still
  // carries its errors. The driver keeps what it compiles in its own cache (PoCL: POCL_CACHE_DIR).
  const std::string build_options = "-cl-std=CL1.2 -w " + options;
  const std::filesystem::path binaries = program_binary_folder();
  const std::string binary_key = binaries.empty() ? std::string() : program_binary_key(device, source, build_options);
  if (!binary_key.empty()) {
    if (std::optional<cl::Program> loaded = load_program_binary(device, binaries, binary_key, build_options)) {
      ++counters().built;
      ++counters().loaded;
      entry.programs.emplace(table_key, *loaded);
      return *loaded;
    }
  }
  cl::Program program(entry.context, source);
  try {
    program.build(std::vector<cl::Device>{device.device}, build_options.c_str());
  } catch (const cl::Error& e) {
    std::string log;
    try {
      log = trim(program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device.device));
    } catch (const cl::Error&) {
      log = "(no build log)";
    }
    throw OpenClError("building an OpenCL program for " + device.device_name + " with options \"" + options +
                      "\" failed (" + describe_cl_error(e) + "); build log:\n" + log);
  }
  // Only when asked: PoCL compiles every kernel once more (for any work-group size) to make the binary.
  if (!binary_key.empty() && keeping_binaries()) store_program_binary(device, binaries, binary_key, program);
  ++counters().built;
  entry.programs.emplace(table_key, program);
  return program;
}

std::filesystem::path driver_cache_dir() {
  ensure_pocl_cache_dir();
  return getenv_or_empty("POCL_CACHE_DIR");
}

std::size_t driver_cache_files() {
  namespace fs = std::filesystem;
  const fs::path dir = driver_cache_dir();
  std::error_code ec;
  if (dir.empty() || !fs::is_directory(dir, ec)) return 0;
  std::size_t count = 0;
  for (auto it = fs::recursive_directory_iterator(dir, fs::directory_options::skip_permission_denied, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const fs::path& file = it->path();
    if (it->is_regular_file(ec) && (file.extension() == ".so" || file.filename() == "program.bc")) ++count;
  }
  return count;
}

}  // namespace texwarp::kernels_detail

namespace texwarp {

bool set_opencl_cache_dir(const std::string& folder) {
  kernels_detail::CacheFolder& c = kernels_detail::cache_folder();
  std::lock_guard lock(c.mutex);
  if (c.chosen) return *c.chosen == std::filesystem::path(folder);
  c.requested = folder;
  return true;
}

void keep_opencl_program_binaries(bool keep) { kernels_detail::keeping_binaries() = keep; }

std::string opencl_cache_dir() { return kernels_detail::cache_dir().string(); }

std::string opencl_driver_cache_dir() { return kernels_detail::driver_cache_dir().string(); }

OpenClActivity opencl_activity() {
  const kernels_detail::Counters& c = kernels_detail::counters();
  return {c.contexts.load(), c.built.load(), c.loaded.load(), kernels_detail::driver_cache_files()};
}

}  // namespace texwarp
