// Backend selection for the CLI: see backend_choice.hpp.
#include "backend_choice.hpp"

#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/proto/input_error.hpp"
#ifdef TEXWARP_HAVE_OPENCL
#include "texwarp/kernels/opencl_backend.hpp"
#endif

namespace texwarp::cli {

const char* default_backend_name() {
#ifdef TEXWARP_HAVE_OPENCL
  return "opencl";
#else
  return "cpu";
#endif
}

void add_backend_options(CLI::App& command, BackendChoice& choice) {
  command.add_option("--backend", choice.backend,
                     std::string("compute backend: cpu (double-precision reference) or opencl (default: ") +
                         default_backend_name() + ")")
      ->check(CLI::IsMember({"cpu", "opencl"}));
  command.add_option("--device", choice.device,
                     "OpenCL device: a name substring, or cpu|gpu|accelerator (default: PoCL on the CPU)");
  command.add_option("--threads", choice.threads, "CPU backend worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
}

std::unique_ptr<WarpBackend> make_backend(const BackendChoice& choice) {
  const std::string name = choice.backend.empty() ? default_backend_name() : choice.backend;
  if (name == "cpu") {
    if (!choice.device.empty()) throw InputError("--device", "only applies to --backend opencl");
    return std::make_unique<CpuBackend>();
  }
#ifdef TEXWARP_HAVE_OPENCL
  OpenClOptions options;
  options.device = choice.device;
  return make_opencl_backend(options);
#else
  throw InputError("--backend", "this build of texwarp has no OpenCL backend");
#endif
}

}  // namespace texwarp::cli
