// `texwarp fetch ID --out DIR`: downloads a succeeded job's result files (each written atomically) from a texwarpd.
#include <filesystem>
#include <iostream>

#include "server_commands.hpp"

namespace texwarp::cli {
namespace {

struct FetchArgs {
  std::string id;
  std::string out;
  std::string file;
  ServerArgs server;
};

int run_fetch(const FetchArgs& args) {
  client::Client client = make_client(args.server);
  if (!args.file.empty()) {
    const auto path = client.fetch_file_to(args.id, args.file, (std::filesystem::path(args.out) / args.file).string());
    if (!path.ok()) return report_client_error(path.error());
    std::cout << path.value() << "\n";
    return kExitOk;
  }
  const auto fetched = client.fetch_results(args.id, args.out);
  if (!fetched.ok()) return report_client_error(fetched.error());
  for (const auto& p : fetched->paths) std::cout << p << "\n";
  return kExitOk;
}

}  // namespace

void add_fetch_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<FetchArgs>();
  CLI::App* cmd =
      root.add_subcommand("fetch", "Download a succeeded job's result files into a folder; prints their paths");
  cmd->add_option("id", args->id, "job id")->required();
  cmd->add_option("--out", args->out, "folder for the files (created if missing)")->required();
  cmd->add_option("--file", args->file, "only this file (e.g. warped.png, report.json)");
  add_server_options(*cmd, args->server);
  cmd->callback([args, &action] { action = [args] { return run_fetch(*args); }; });
}

}  // namespace texwarp::cli
