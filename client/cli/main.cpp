// `texwarp`: the command line for farms and scripts. Exit codes: 0 success, 2 invalid input (message on
// stderr naming what is wrong), 3 interrupted or the job canceled, 1 any other failure.
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "cli_command.hpp"
#include "map_mesh_command.hpp"
#include "server_commands.hpp"
#include "texwarp/build_info.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/input_error.hpp"

namespace {

int run_cli(int argc, char** argv) {
  using namespace texwarp::cli;
  CLI::App app("texwarp: constrained texture mapping by foldover-free image warping (Seo & Cordier)");
  app.footer(
      "Exit codes: 0 success, 2 invalid input (the message names the file and JSON path), 1 other failure, "
      "3 interrupted (SIGINT, SIGTERM: warp, map-mesh, map and run leave no partial output) or the job was canceled "
      "(submit/wait/cancel), 4 timed out.");
  app.set_version_flag("--version", texwarp::version_line("texwarp"),
                       "print the version and the git commit texwarp was built from, and exit");
  app.require_subcommand(1);
  Action action;
  add_map_command(app, action);
  add_warp_command(app, action);
  add_check_command(app, action);
  add_devices_command(app, action);
  add_warm_command(app, action);
  add_map_mesh_command(app, action);
  add_run_command(app, action);
  add_submit_command(app, action);
  add_status_command(app, action);
  add_wait_command(app, action);
  add_fetch_command(app, action);
  add_cancel_command(app, action);
  add_purge_command(app, action);
  add_list_command(app, action);
  add_nodes_command(app, action);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitInvalidInput;
  }
  try {
    return action ? action() : kExitInvalidInput;
  } catch (const texwarp::CanceledError&) {
    // SIGINT or SIGTERM while a command's work ran (InterruptCancel): it unwound, removing what it had staged.
    const std::string command = app.get_subcommands().empty() ? "" : " " + app.get_subcommands().front()->get_name();
    std::fprintf(stderr, "texwarp:%s: interrupted; no output was written\n", command.c_str());
    return kExitCanceled;
  } catch (const texwarp::InputError& e) {
    std::fprintf(stderr, "texwarp: invalid input: %s\n", e.what());
    return kExitInvalidInput;
  } catch (const std::bad_alloc&) {
    // What the memory estimate did not foresee (or a budget set above what the machine can give).
    const std::string command = app.get_subcommands().empty() ? "" : " " + app.get_subcommands().front()->get_name();
    std::fprintf(stderr,
                 "texwarp: error: out of memory while running `texwarp%s`: this machine could not give it the memory "
                 "it needed (try smaller images or output sizes)\n",
                 command.c_str());
    return kExitFailure;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "texwarp: error: %s\n", e.what());
    return kExitFailure;
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run_cli(argc, argv);
  } catch (...) {
    // What run_cli's own handlers do not answer: the command line's set-up failing, a handler out of memory.
    std::fputs("texwarp: error: an unexpected failure\n", stderr);
    return texwarp::cli::kExitFailure;
  }
}
