// The `texwarp` command line's plumbing: each subcommand registers itself on the CLI11 app and sets the
// action to run; main() runs it and turns exceptions into exit codes (0 ok, 2 invalid input, 3 interrupted, 1 other
// failure).
#pragma once

#include <functional>
#include <string>

#include <CLI/CLI.hpp>

namespace texwarp::cli {

using Action = std::function<int()>;

// Exit codes, documented in `texwarp --help` and the README.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitInvalidInput = 2;
inline constexpr int kExitCanceled = 3;  // the job was canceled, or the command interrupted (SIGINT, SIGTERM)

// Each adds its subcommand to `root`; when parsed, the subcommand stores its action in `action`.
void add_map_command(CLI::App& root, Action& action);
void add_warp_command(CLI::App& root, Action& action);
void add_check_command(CLI::App& root, Action& action);
void add_devices_command(CLI::App& root, Action& action);  // lists the OpenCL devices (backend_choice.cpp)
void add_warm_command(CLI::App& root, Action& action);     // compiles the kernels into the cache (backend_choice.cpp)

}  // namespace texwarp::cli
