// `texwarp submit JOB.json`: sends a job file to a texwarpd (optionally uploading the local files it names first),
// prints the accepted job's status, and with --wait/--out waits for it and downloads its results. Every request
// outlives a server restart within --retry-budget; the submission's Idempotency-Key keeps its resends one job.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "feature_file.hpp"
#include "server_commands.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::cli {
namespace {

namespace fs = std::filesystem;

struct SubmitArgs {
  std::string job;
  std::string idempotency_key;
  bool upload = false;
  bool wait = false;
  std::string out;
  double timeout_s = 0.0;
  bool quiet = false;
  ServerArgs server;
};

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(InputLocation::file(path), "cannot open the file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A path in the job, relative to the job file's folder when not absolute.
fs::path local_path(const std::string& job_file, const std::string& path) {
  const fs::path p(path);
  return p.is_absolute() ? p : fs::path(job_file).parent_path() / p;
}

int run_submit(const SubmitArgs& args) {
  client::Client client = make_client(args.server);
  std::string body = read_text(args.job);
  if (args.upload) {
    // Local files named by path become blobs, so that the job needs nothing from the server's filesystem.
    proto::JobSpec spec = in_file(args.job, [&] { return proto::decode_job_spec(proto::parse_json(body, args.job)); });
    if (spec.image.kind == proto::ImageSourceSpec::Kind::kPath) {
      const auto blob = client.upload_file(local_path(args.job, spec.image.path).string());
      if (!blob.ok()) return report_client_error(blob.error());
      spec.image = {proto::ImageSourceSpec::Kind::kBlob, blob->id, {}, {}};
    }
    if (spec.mesh && spec.mesh->source.kind == proto::MeshSourceSpec::Kind::kPath) {
      const auto blob = client.upload_file(local_path(args.job, spec.mesh->source.path).string());
      if (!blob.ok()) return report_client_error(blob.error());
      spec.mesh->source.kind = proto::MeshSourceSpec::Kind::kBlob;
      spec.mesh->source.blob = blob->id;
    }
    body = proto::encode_job_spec(spec).dump();
  }
  const auto submitted = client.submit_json(body, args.idempotency_key);
  if (!submitted.ok()) return report_client_error(submitted.error());
  const std::string id = submitted->id;
  if (!args.wait && args.out.empty()) {
    std::cout << proto::encode_job_status(submitted.value()).dump(2) << "\n";
    return kExitOk;
  }
  if (!args.quiet) std::fprintf(stderr, "texwarp: submitted job %s\n", id.c_str());
  const int waited = wait_for_job(client, id, args.timeout_s, args.quiet);
  if (waited != kExitOk || args.out.empty()) return waited;
  const auto fetched = client.fetch_results(id, args.out);
  if (!fetched.ok()) return report_client_error(fetched.error());
  for (const auto& p : fetched->paths) std::fprintf(stderr, "texwarp: wrote %s\n", p.c_str());
  return kExitOk;
}

}  // namespace

void add_submit_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<SubmitArgs>();
  CLI::App* cmd = root.add_subcommand(
      "submit", "Submit a job file to a texwarpd; prints the job (JSON). With --wait/--out: waits, downloads results");
  cmd->add_option("job", args->job, "job file (JSON, see examples/*job*.json)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--idempotency-key", args->idempotency_key,
                  "resubmitting with the same key returns the same job instead of a new one (default: a random key)");
  cmd->add_flag("--upload", args->upload,
                "upload the local image/mesh files the job names by path (relative to the job file) as blobs first");
  cmd->add_flag("--wait", args->wait, "wait for the job; exit 0 succeeded, 1 failed, 3 canceled, 4 timed out");
  cmd->add_option("--out", args->out, "wait, then download the result files into this folder");
  cmd->add_option("--timeout", args->timeout_s, "with --wait/--out: give up after this many seconds")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--quiet", args->quiet, "no progress lines on stderr");
  add_server_options(*cmd, args->server);
  cmd->callback([args, &action] { action = [args] { return run_submit(*args); }; });
}

}  // namespace texwarp::cli
