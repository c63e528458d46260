// `texwarp list [--state S] [--label KEY=VALUE]…`: a page of a texwarpd's jobs, newest first, filtered by state and
// labels (all must match), as JSON with the cursor of the next page.
#include <iostream>

#include "label_flags.hpp"
#include "server_commands.hpp"
#include "texwarp/proto/job_status_codec.hpp"

namespace texwarp::cli {
namespace {

struct ListArgs {
  int limit = 20;
  std::string state;
  std::vector<std::string> labels;
  std::string cursor;
  ServerArgs server;
};

int run_list(const ListArgs& args) {
  client::ListOptions options;
  options.limit = args.limit;
  options.cursor = args.cursor;
  options.labels = parse_label_flags(args.labels);
  if (!args.state.empty())
    options.state = proto::parse_enum<proto::JobState>(args.state, InputLocation::flag("--state"));
  client::Client client = make_client(args.server);
  const auto page = client.list(options);
  if (!page.ok()) return report_client_error(page.error());
  std::cout << proto::encode_job_page(page.value()).dump(2) << "\n";
  return kExitOk;
}

}  // namespace

void add_list_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<ListArgs>();
  CLI::App* cmd = root.add_subcommand(
      "list", "List jobs, newest first, filtered by state and labels; prints a page (JSON) with its next_cursor");
  cmd->add_option("--state", args->state, "only jobs in this state")
      ->check(CLI::IsMember(proto::enum_names<proto::JobState>()));
  cmd->add_option("--label", args->labels, "KEY=VALUE: only jobs with this label (repeatable; all must match)");
  cmd->add_option("--limit", args->limit, "jobs per page (1-500, default 20)")->check(CLI::Range(1, 500));
  cmd->add_option("--cursor", args->cursor, "next_cursor of the previous page");
  add_server_options(*cmd, args->server);
  cmd->callback([args, &action] { action = [args] { return run_list(*args); }; });
}

}  // namespace texwarp::cli
