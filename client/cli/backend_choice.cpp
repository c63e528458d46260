// Backend selection for the CLI: see backend_choice.hpp.
#include "backend_choice.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

#include "cli_command.hpp"
#include "command_clock.hpp"

#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/kernels/opencl_backend.hpp"
#include "texwarp/kernels/opencl_error.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::cli {

const char* default_backend_name() { return "opencl"; }

void add_backend_options(CLI::App& command, BackendChoice& choice) {
  command
      .add_option("--backend", choice.backend,
                  std::string("compute backend: cpu (double-precision reference) or opencl (default: ") +
                      default_backend_name() + ")")
      ->check(CLI::IsMember({"cpu", "opencl"}));
  command.add_option("--device", choice.device,
                     "OpenCL device: a name substring, or cpu|gpu|accelerator (default: PoCL on the CPU)");
  command.add_option("--threads", choice.threads, "CPU backend worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
}

proto::DeviceSpec chosen_device(const BackendChoice& choice) {
  const std::string name = choice.backend.empty() ? default_backend_name() : choice.backend;
  if (name == "cpu") {
    if (!choice.device.empty()) throw InputError(InputLocation::flag("--device"), "only applies to --backend opencl");
    return proto::DeviceSpec::cpu();
  }
  return proto::DeviceSpec::opencl(choice.device);
}

std::unique_ptr<WarpBackend> make_backend(const BackendChoice& choice) {
  const proto::DeviceSpec device = chosen_device(choice);
  if (device.kind == proto::DeviceSpec::Kind::kCpu) return std::make_unique<CpuBackend>();
  OpenClOptions options;
  options.device = device.name;
  try {
    return make_opencl_backend(options);
  } catch (const OpenClNoMatchingDevice& e) {
    // A --device that names no device is a usage error (exit 2; the message lists the devices there are). Any
    // other OpenCL failure (no platform, no context) stays a failure of the run (exit 1).
    throw InputError(InputLocation::flag("--device"), e.what());
  }
}

void add_devices_command(CLI::App& root, Action& action) {
  CLI::App* cmd =
      root.add_subcommand("devices", "List the OpenCL devices --device can name ([default] marks PoCL's CPU)");
  cmd->callback([&action] {
    action = [] {
      const std::vector<std::string> devices = list_opencl_devices();
      if (devices.empty()) {
        std::fprintf(stderr, "texwarp: no OpenCL platform found (install pocl-opencl-icd)\n");
        return kExitFailure;
      }
      for (const std::string& d : devices) std::printf("%s\n", d.c_str());
      return kExitOk;
    };
  });
}

namespace {

// The kernel variants warm_opencl_programs builds and launches on a device with cl_khr_fp64 (PoCL's CPU device):
// float and double, each with and without the Jacobian. The progress's denominator; a device without fp64 builds
// half of them and its progress jumps to 100 % at the end.
constexpr std::size_t kWarmVariants = 4;
constexpr auto kWarmPoll = std::chrono::milliseconds(100);

// Runs warm_opencl_programs while a thread reads how many programs this process has built (opencl_activity): each
// variant's build and then its first launch (the driver's compile of the launch shape) is half of its share, so
// `progress` reaches (2k − 1) / 2V when the k-th program is built, and 1 when warm returns.
OpenClWarmth warm_with_progress(const OpenClOptions& options, const std::function<void(double)>& progress) {
  if (!progress) return warm_opencl_programs(options);
  opencl_driver_cache_dir();  // decides the cache folder (and its environment) before a second thread reads it
  const std::size_t built_before = opencl_activity().programs_built;
  std::mutex mutex;
  std::condition_variable wake;
  bool done = false;
  std::thread poll([&] {
    std::unique_lock lock(mutex);
    while (!wake.wait_for(lock, kWarmPoll, [&] { return done; })) {
      const std::size_t built = std::min(opencl_activity().programs_built - built_before, kWarmVariants);
      if (built > 0) progress((2.0 * static_cast<double>(built) - 1.0) / (2.0 * kWarmVariants));
    }
  });
  const auto stop = [&] {
    {
      std::lock_guard lock(mutex);
      done = true;
    }
    wake.notify_all();
    poll.join();
  };
  try {
    const OpenClWarmth warmth = warm_opencl_programs(options);
    stop();
    return warmth;
  } catch (...) {
    stop();
    throw;
  }
}

}  // namespace

void add_warm_command(CLI::App& root, Action& action) {
  struct WarmArgs {
    std::string device;
    bool progress = false;
    std::string timings;  // "", "table" or "json"
  };
  auto args = std::make_shared<WarmArgs>();
  CLI::App* cmd = root.add_subcommand(
      "warm", "Compile the OpenCL kernels now and keep them in the cache folder, so that the first warp starts warm");
  cmd->add_option("--device", args->device, "OpenCL device: a name substring, or cpu|gpu|accelerator (default: PoCL)");
  add_progress_option(*cmd, args->progress);
  add_timings_option(*cmd, args->timings);
  cmd->callback([args, &action] {
    action = [args] {
      using proto::LatencyStage;
      // Warming is device set-up alone: opening the device, building each variant's program, launching it once.
      CommandClock clock({LatencyStage::kStartup, LatencyStage::kDeviceSetup}, args->progress);
      const auto start = std::chrono::steady_clock::now();
      OpenClOptions options;
      options.device = args->device;
      keep_opencl_program_binaries();  // for the commands after warm: see opencl_backend.hpp
      const OpenClWarmth warmth = clock.time(LatencyStage::kDeviceSetup, [&] {
        try {
          return warm_with_progress(options, clock.progress_within(LatencyStage::kDeviceSetup));
        } catch (const OpenClNoMatchingDevice& e) {
          throw InputError(InputLocation::flag("--device"), e.what());
        }
      });
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      clock.finish(args->timings);
      std::fprintf(stderr,
                   "texwarp: kernels ready in %.2f s (%zu variants launched, %zu files compiled); cache folder %s "
                   "(driver's cache %s)\n",
                   seconds, warmth.variants, warmth.files_compiled, opencl_cache_dir().c_str(),
                   opencl_driver_cache_dir().c_str());
      return kExitOk;
    };
  });
}

void say_double_retries(const WarpBackend& backend, const char* command) {
  const std::uint64_t n = backend.double_retries();
  if (n == 0) return;
  std::fprintf(stderr,
               "texwarp: %s: %llu pathline call%s ran again in double: float32's steps collapsed where paths pass "
               "within about a pixel (the results are double's)\n",
               command, static_cast<unsigned long long>(n), n == 1 ? "" : "s");
}

}  // namespace texwarp::cli
