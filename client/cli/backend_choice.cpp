// Backend selection for the CLI: see backend_choice.hpp.
#include "backend_choice.hpp"

#include <chrono>
#include <cstdio>
#include <memory>

#include "cli_command.hpp"

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

void add_warm_command(CLI::App& root, Action& action) {
  auto device = std::make_shared<std::string>();
  CLI::App* cmd = root.add_subcommand(
      "warm", "Compile the OpenCL kernels now and keep them in the cache folder, so that the first warp starts warm");
  cmd->add_option("--device", *device, "OpenCL device: a name substring, or cpu|gpu|accelerator (default: PoCL)");
  cmd->callback([device, &action] {
    action = [device] {
      const auto start = std::chrono::steady_clock::now();
      OpenClOptions options;
      options.device = *device;
      OpenClWarmth warmth;
      try {
        warmth = warm_opencl_programs(options);
      } catch (const OpenClNoMatchingDevice& e) {
        throw InputError(InputLocation::flag("--device"), e.what());
      }
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      std::fprintf(stderr,
                   "texwarp: kernels ready in %.2f s (%zu variants launched, %zu files compiled); cache folder %s "
                   "(driver's cache %s)\n",
                   seconds, warmth.variants, warmth.files_compiled, opencl_cache_dir().c_str(),
                   opencl_driver_cache_dir().c_str());
      return kExitOk;
    };
  });
}

}  // namespace texwarp::cli
