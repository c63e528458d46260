// Choosing the compute backend from the command line: --backend cpu|opencl, --device NAME, --threads N.
#pragma once

#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "texwarp/core/warp_backend.hpp"
#include "texwarp/proto/device_spec.hpp"

namespace texwarp::cli {

struct BackendChoice {
  std::string backend;  // empty: the default (opencl when built with it, else cpu)
  std::string device;   // OpenCL device: name substring or cpu|gpu|accelerator
  int threads = 0;      // CPU backend threads; 0 = all
};

void add_backend_options(CLI::App& command, BackendChoice& choice);
// The device the flags name: --backend (default: default_backend_name()) with --device for OpenCL. InputError at
// --device when it is given with the CPU backend.
proto::DeviceSpec chosen_device(const BackendChoice& choice);
std::unique_ptr<WarpBackend> make_backend(const BackendChoice& choice);
const char* default_backend_name();
// A line on stderr ("texwarp: <command>: …") when the backend ran calls again in double (float32's steps collapsed).
void say_double_retries(const WarpBackend& backend, const char* command);

}  // namespace texwarp::cli
