// A DCC plugin as a shared object: one C entry point that runs a job (JSON text) on texwarpd through the installed
// libtexwarp_client. Built with default visibility (as plugin authors do), so `nm -D` shows what it exports.
#include <cstdio>

#include "texwarp/client/client.hpp"

extern "C" int texwarp_plugin_run(const char* server, const char* job_json, const char* out_dir) {
  texwarp::client::ClientOptions options;
  options.server = server;
  texwarp::client::Client client(options);
  const auto submitted = client.submit_json(job_json);
  if (!submitted) {
    std::fprintf(stderr, "submit: %s\n", submitted.error().message.c_str());
    return 1;
  }
  const auto done = client.wait(submitted->id);
  if (!done || done->state != texwarp::proto::JobState::kSucceeded) return 1;
  const auto files = client.fetch_results(submitted->id, out_dir);
  return files ? static_cast<int>(files->paths.size()) : -1;
}
