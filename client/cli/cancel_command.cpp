// `texwarp cancel ID`: cancels a queued or running job on a texwarpd and prints its status.
#include <cstdio>
#include <iostream>

#include "server_commands.hpp"
#include "texwarp/proto/job_status_codec.hpp"

namespace texwarp::cli {
namespace {

struct CancelArgs {
  std::string id;
  bool wait = false;
  ServerArgs server;
};

int run_cancel(const CancelArgs& args) {
  client::Client client = make_client(args.server);
  const auto s = client.cancel(args.id);
  if (!s.ok()) return report_client_error(s.error());
  proto::JobStatus status = s.value();
  if (args.wait && !proto::is_terminal(status.state)) {
    const auto done = client.wait(args.id);
    if (!done.ok()) return report_client_error(done.error());
    status = done.value();
  }
  std::cout << proto::encode_job_status(status).dump(2) << "\n";
  if (args.wait && status.state != proto::JobState::kCanceled) {
    std::fprintf(stderr, "texwarp: job %s %s before the cancellation took effect\n", args.id.c_str(),
                 proto::to_string(status.state));
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void add_cancel_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<CancelArgs>();
  CLI::App* cmd =
      root.add_subcommand("cancel", "Cancel a queued or running job on a texwarpd (exit 2 if it already finished)");
  cmd->add_option("id", args->id, "job id")->required();
  cmd->add_flag("--wait", args->wait,
                "wait until a running job has stopped; exit 1 if it finished before the cancellation took effect");
  add_server_options(*cmd, args->server);
  cmd->callback([args, &action] { action = [args] { return run_cancel(*args); }; });
}

}  // namespace texwarp::cli
