// `texwarp wait ID`: waits for a job on a texwarpd (long-poll), with progress lines, and exits by its final state;
// a server that restarts meanwhile is waited for (each request retries within --retry-budget, --timeout still ends
// the wait).
#include <cstdio>
#include <iostream>

#include "server_commands.hpp"
#include "texwarp/proto/job_status_codec.hpp"

namespace texwarp::cli {
namespace {

struct WaitArgs {
  std::string id;
  double timeout_s = 0.0;
  bool quiet = false;
  ServerArgs server;
};

}  // namespace

int wait_for_job(client::Client& client, const std::string& id, double timeout_s, bool quiet) {
  client::WaitOptions options;
  options.timeout = std::chrono::milliseconds(static_cast<long long>(timeout_s * 1000.0));
  if (!quiet) {
    options.on_progress = [](const proto::JobStatus& s) {
      std::fprintf(stderr, "texwarp: job %s %s %d%%\n", s.id.c_str(), proto::to_string(s.state), s.progress);
    };
  }
  const auto done = client.wait(id, options);
  if (!done.ok()) return report_client_error(done.error());
  std::cout << proto::encode_job_status(done.value()).dump(2) << "\n";
  switch (done->state) {
    case proto::JobState::kSucceeded:
      return kExitOk;
    case proto::JobState::kCanceled:
      std::fprintf(stderr, "texwarp: job %s was canceled\n", id.c_str());
      return kExitCanceled;
    default:
      std::fprintf(stderr, "texwarp: job %s failed: %s%s\n", id.c_str(),
                   done->error ? done->error->detail.c_str() : "(no error given)",
                   done->error && !done->error->path.empty() ? (" [at " + done->error->path + "]").c_str() : "");
      return kExitFailure;
  }
}

void add_wait_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<WaitArgs>();
  CLI::App* cmd = root.add_subcommand(
      "wait", "Wait for a job on a texwarpd (outliving a server restart); exit 0 succeeded, 1 failed, 3 canceled, "
              "4 timed out");
  cmd->add_option("id", args->id, "job id (as submit printed it)")->required();
  cmd->add_option("--timeout", args->timeout_s, "give up after this many seconds (default: wait as long as it takes)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quiet", args->quiet, "no progress lines on stderr");
  add_server_options(*cmd, args->server);
  cmd->callback([args, &action] {
    action = [args] {
      client::Client client = make_client(args->server);
      return wait_for_job(client, args->id, args->timeout_s, args->quiet);
    };
  });
}

}  // namespace texwarp::cli
