// `texwarp nodes`: the texwarpd nodes that share the server's job store, with their heartbeats, as JSON.
#include <iostream>

#include "server_commands.hpp"
#include "texwarp/proto/node_status_codec.hpp"

namespace texwarp::cli {
namespace {

struct NodesArgs {
  ServerArgs server;
};

int run_nodes(const NodesArgs& args) {
  client::Client client = make_client(args.server);
  const auto nodes = client.nodes();
  if (!nodes.ok()) return report_client_error(nodes.error());
  std::cout << proto::encode_node_list(nodes.value()).dump(2) << "\n";
  return kExitOk;
}

}  // namespace

void add_nodes_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<NodesArgs>();
  CLI::App* cmd = root.add_subcommand(
      "nodes",
      "List the texwarpd nodes sharing the job store (JSON: id, address, version, workers, alive, running...)");
  add_server_options(*cmd, args->server);
  cmd->callback([args, &action] { action = [args] { return run_nodes(*args); }; });
}

}  // namespace texwarp::cli
