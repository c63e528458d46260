// `texwarp submit JOB.json…`: sends job files to a texwarpd (optionally uploading the local files they name first,
// with --priority and --label applied to each), one file as a job, several as one all-or-nothing batch; prints the
// accepted status(es), and for one job with --wait/--out waits for it and downloads its results. Every request
// outlives a server restart within --retry-budget; the submission's Idempotency-Key keeps its resends one job each.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <vector>

#include "feature_file.hpp"
#include "label_flags.hpp"
#include "server_commands.hpp"
#include "texwarp/core/udim_texture.hpp"
#include "texwarp/proto/job_batch_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::cli {
namespace {

namespace fs = std::filesystem;

struct SubmitArgs {
  std::vector<std::string> jobs;
  std::optional<int> priority;
  std::vector<std::string> labels;
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

// An upload that failed while a job was prepared, carried out to run_submit, which reports it.
struct UploadFailed {
  client::ClientError error;
};

// The job file as it is sent: decoded (errors name the file and the JSON path), its local files uploaded with
// --upload, --priority and --label applied (a flag's label replaces the file's label of the same key).
proto::JobSpec prepare_job(client::Client& client, const SubmitArgs& args, const std::string& file,
                           const proto::JobLabels& labels) {
  const std::string body = read_text(file);
  proto::JobSpec spec = in_file(file, [&] { return proto::decode_job_spec(proto::parse_json(body, file)); });
  if (args.upload) {
    // Local files named by path become blobs, so that the job needs nothing from the server's filesystem.
    const auto upload = [&](proto::ImageSourceSpec& image) {
      if (image.kind != proto::ImageSourceSpec::Kind::kPath) return;
      if (has_udim_token(image.path)) {
        // A <UDIM> path: the tiles that exist here, each uploaded, sent as the texture's "tiles".
        // Found (and checked alike) as a local run finds them, before anything is sent.
        const std::string pattern = local_path(file, image.path).string();
        const UdimCanvas canvas =
            find_udim_tiles(image.path, InputLocation::file(file), {}, [&](int n) -> std::optional<std::string> {
              std::error_code ec;
              const std::string tile = udim_tile_path(pattern, n);
              return fs::is_regular_file(tile, ec) ? std::optional(tile) : std::nullopt;
            });
        std::vector<proto::UdimTileSource> tiles;
        for (const UdimTile& t : canvas.tiles) {
          const auto blob = client.upload_file(t.file);
          if (!blob.ok()) throw UploadFailed{blob.error()};
          tiles.push_back({t.number, blob->id, {}});
        }
        image.kind = proto::ImageSourceSpec::Kind::kTiles;
        image.tiles = std::move(tiles);
        image.path.clear();
        return;
      }
      const auto blob = client.upload_file(local_path(file, image.path).string());
      if (!blob.ok()) throw UploadFailed{blob.error()};
      image.kind = proto::ImageSourceSpec::Kind::kBlob;  // what the image holds (role, …) stays
      image.blob = blob->id;
      image.path.clear();
    };
    if (!spec.is_set()) upload(spec.image);
    // A set's maps keep their names (decoded from the paths when not given) when they become blobs.
    for (proto::NamedImageSpec& entry : spec.images) upload(entry.source);
    if (spec.mesh && spec.mesh->source.kind == proto::MeshSourceSpec::Kind::kPath) {
      const auto blob = client.upload_file(local_path(file, spec.mesh->source.path).string());
      if (!blob.ok()) throw UploadFailed{blob.error()};
      spec.mesh->source.kind = proto::MeshSourceSpec::Kind::kBlob;
      spec.mesh->source.blob = blob->id;
    }
  }
  if (args.priority) spec.priority = *args.priority;
  for (const auto& [key, value] : labels) spec.labels[key] = value;
  if (spec.labels.size() > proto::kMaxJobLabels) {
    throw InputError(InputLocation::flag("--label").in_file(file),
                     "the job's labels and --label make " + std::to_string(spec.labels.size()) + ", at most " +
                         std::to_string(proto::kMaxJobLabels) + " are allowed");
  }
  return spec;
}

// Several files: one batch, accepted all or none; prints {"jobs": [status, …]} in the files' order.
int submit_batch(client::Client& client, const SubmitArgs& args, const proto::JobLabels& labels) {
  std::vector<proto::JobSpec> specs;
  for (const auto& file : args.jobs) specs.push_back(prepare_job(client, args, file, labels));
  const auto submitted = client.submit_batch(specs, args.idempotency_key);
  if (!submitted.ok()) {
    const auto& e = submitted.error();
    if (e.batch_index && *e.batch_index < args.jobs.size()) {
      std::fprintf(stderr, "texwarp: %s was refused; no job of the batch was submitted\n",
                   args.jobs[*e.batch_index].c_str());
    }
    return report_client_error(e);
  }
  std::cout << proto::encode_job_batch_status(proto::JobBatchStatus{submitted.value()}).dump(2) << "\n";
  return kExitOk;
}

int submit_jobs(const SubmitArgs& args) {
  client::Client client = make_client(args.server);
  const proto::JobLabels labels = parse_label_flags(args.labels);
  if (args.jobs.size() > 1) {
    if (args.wait || !args.out.empty()) {
      throw InputError(InputLocation::flag(args.wait ? "--wait" : "--out"),
                       "takes one job file; with several, run `texwarp wait ID` for each printed job");
    }
    return submit_batch(client, args, labels);
  }
  const std::string& file = args.jobs.front();
  // Sent as written unless something is to change in it (errors then still come from the server, at their path).
  std::string body = read_text(file);
  if (args.upload || args.priority || !labels.empty()) {
    body = proto::encode_job_spec(prepare_job(client, args, file, labels)).dump();
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

int run_submit(const SubmitArgs& args) {
  try {
    return submit_jobs(args);
  } catch (const UploadFailed& failed) {
    return report_client_error(failed.error);
  }
}

}  // namespace

void add_submit_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<SubmitArgs>();
  CLI::App* cmd = root.add_subcommand(
      "submit", "Submit job files to a texwarpd (several: one batch, all or none); prints the job (JSON; several: "
                "{\"jobs\": [...]} in the files' order). With --wait/--out (one file): waits, downloads results");
  cmd->add_option("jobs", args->jobs, "job files (JSON, see examples/*job*.json)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--priority", args->priority,
                  "queue priority of every job, -1000 to 1000 (higher runs first; default: the file's, else 0)")
      ->check(CLI::Range(proto::kMinJobPriority, proto::kMaxJobPriority));
  cmd->add_option("--label", args->labels,
                  "KEY=VALUE label for every job (repeatable; replaces the file's label of that key); keys are 1-63 "
                  "of A-Z a-z 0-9 _ . - /, values up to 256 bytes of UTF-8");
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
