// `texwarp status [ID]`: one job's status as JSON, or (no id) the newest jobs, from a texwarpd.
#include <iostream>

#include "server_commands.hpp"
#include "texwarp/proto/job_status_codec.hpp"

namespace texwarp::cli {
namespace {

struct StatusArgs {
  std::string id;
  int limit = 20;
  std::string state;
  std::string cursor;
  ServerArgs server;
};

int run_status(const StatusArgs& args) {
  client::Client client = make_client(args.server);
  if (!args.id.empty()) {
    const auto s = client.status(args.id);
    if (!s.ok()) return report_client_error(s.error());
    std::cout << proto::encode_job_status(s.value()).dump(2) << "\n";
    return kExitOk;
  }
  client::ListOptions options;
  options.limit = args.limit;
  options.cursor = args.cursor;
  if (!args.state.empty())
    options.state = proto::parse_enum<proto::JobState>(args.state, InputLocation::flag("--state"));
  const auto page = client.list(options);
  if (!page.ok()) return report_client_error(page.error());
  std::cout << proto::encode_job_page(page.value()).dump(2) << "\n";
  return kExitOk;
}

}  // namespace

void add_status_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<StatusArgs>();
  CLI::App* cmd = root.add_subcommand("status", "Print a job's status (JSON), or list the newest jobs without an id");
  cmd->add_option("id", args->id, "job id; omit to list jobs");
  cmd->add_option("--limit", args->limit, "jobs per page when listing (1-500, default 20)")->check(CLI::Range(1, 500));
  cmd->add_option("--state", args->state, "list only jobs in this state")
      ->check(CLI::IsMember(proto::enum_names<proto::JobState>()));
  cmd->add_option("--cursor", args->cursor, "next_cursor of the previous page");
  add_server_options(*cmd, args->server);
  cmd->callback([args, &action] { action = [args] { return run_status(*args); }; });
}

}  // namespace texwarp::cli
