// `texwarp purge ID`: deletes a finished job's record and result files from a texwarpd (a queued or running job is
// left alone: exit 2; `texwarp cancel` stops one).
#include <cstdio>

#include "server_commands.hpp"

namespace texwarp::cli {
namespace {

struct PurgeArgs {
  std::string id;
  bool quiet = false;
  ServerArgs server;
};

int run_purge(const PurgeArgs& args) {
  client::Client client = make_client(args.server);
  const auto purged = client.purge(args.id);
  if (!purged.ok()) return report_client_error(purged.error());
  if (!args.quiet) std::fprintf(stderr, "texwarp: purged job %s\n", args.id.c_str());
  return kExitOk;
}

}  // namespace

void add_purge_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<PurgeArgs>();
  CLI::App* cmd = root.add_subcommand(
      "purge", "Delete a finished job and its result files from a texwarpd (exit 2 if it is queued or running)");
  cmd->add_option("id", args->id, "job id")->required();
  cmd->add_flag("--quiet", args->quiet, "no line on stderr");
  add_server_options(*cmd, args->server);
  cmd->callback([args, &action] { action = [args] { return run_purge(*args); }; });
}

}  // namespace texwarp::cli
