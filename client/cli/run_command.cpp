// `texwarp run JOB.json --out DIR`: runs a job file here, with no server (a farm task): the same pipeline as
// texwarpd's workers, progress lines on stderr, result files moved into DIR only once all of them are written.
// SIGINT/SIGTERM cancel it (exit 3) and leave DIR as it was.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

#include "backend_choice.hpp"
#include "command_clock.hpp"
#include "feature_file.hpp"
#include "interrupt_cancel.hpp"
#include "server_commands.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/runner/fsync_path.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/runner/local_input_resolver.hpp"

namespace texwarp::cli {
namespace {

namespace fs = std::filesystem;

struct RunArgs {
  std::string job;
  std::string out;
  bool quiet = false;
  std::string timings;                  // "", "table" or "json"
  std::uint64_t max_job_memory_mb = 0;  // 0: half the machine's memory
  BackendChoice backend;
};

// The flags' device when --backend or --device is given, else the job's.
std::optional<proto::DeviceSpec> device_of(const BackendChoice& choice,
                                           const std::optional<proto::DeviceSpec>& job_device) {
  if (choice.backend.empty() && choice.device.empty()) return job_device;
  return chosen_device(choice);
}

int run_job_file(const RunArgs& args) {
  using proto::LatencyStage;
  CommandClock clock({LatencyStage::kStartup, LatencyStage::kPlan, LatencyStage::kDeviceSetup, LatencyStage::kDecode,
                      LatencyStage::kMapping, LatencyStage::kPathlines, LatencyStage::kSampling, LatencyStage::kVerify,
                      LatencyStage::kEncode, LatencyStage::kWrite},
                     !args.quiet);
  const auto start = std::chrono::steady_clock::now();
  const nlohmann::json j = read_json_file(args.job);
  proto::JobSpec spec = in_file(args.job, [&] { return proto::decode_job_spec(j); });
  spec.options.device = device_of(args.backend, spec.options.device);

  // Interrupts cancel from here on (before the work folder exists): a signal before run_job starts cancels it at once.
  std::optional<InterruptCancel> interrupts(std::in_place);
  const fs::path out(args.out);
  fs::create_directories(out);
  const fs::path work = out / (".texwarp-run-" + std::to_string(::getpid()));
  fs::remove_all(work);
  fs::create_directories(work);
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{work};

  runner::LocalInputResolver inputs(fs::absolute(args.job).parent_path(), work);
  runner::BackendCache backends;
  runner::JobLimits limits;
  limits.max_job_memory_bytes = memory_budget_from_mib(args.max_job_memory_mb, 1);
  RunControl control;
  control.threads = args.backend.threads;
  control.cancel = interrupts->flag();
  // The job's own progress covers it whole (plan to report); the clock keeps it monotone and ticking.
  if (!args.quiet) control.progress = [&clock](double fraction) { clock.set_fraction(fraction); };
  runner::JobOutput output;
  try {
    output = in_file(args.job, [&] { return runner::run_job(spec, inputs, backends, work, limits, control); });
  } catch (const CanceledError&) {
    std::fprintf(stderr, "texwarp: run: canceled; %s left as it was\n", args.out.c_str());
    return kExitCanceled;
  }
  interrupts.reset();
  for (const auto& [stage, name] : proto::EnumNames<LatencyStage>::kTable) {
    if (const auto s = output.report.timings.stages[stage]; s && stage != LatencyStage::kStartup) clock.add(stage, *s);
  }
  // Every file is complete: move them into place (each rename is atomic), then sync the folder.
  clock.time(LatencyStage::kWrite, [&] {
    for (const auto& f : output.files) fs::rename(work / f.name, out / f.name);
    runner::fsync_path(out);
  });
  clock.finish(args.timings);
  for (const auto& f : output.files) std::cout << (out / f.name).string() << "\n";
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::fprintf(stderr, "texwarp: run: %s job on %s in %.2f s; %zu files in %s\n", proto::to_string(spec.kind()),
               output.report.backend.c_str(), seconds, output.files.size(), args.out.c_str());
  return kExitOk;
}

}  // namespace

void add_run_command(CLI::App& root, Action& action) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = root.add_subcommand(
      "run", "Run a job file here, without a server (farm tasks); exit 0 ok, 2 invalid job, 1 failure, 3 canceled");
  cmd->add_option("job", args->job, "job file (JSON, the body of POST /v1/jobs; paths relative to it)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "folder for the result files (created if missing)")->required();
  cmd->add_flag("--quiet", args->quiet, "no 'progress N%' lines on stderr");
  add_timings_option(*cmd, args->timings);
  cmd->add_option("--max-job-memory-mb", args->max_job_memory_mb,
                  "refuse a job estimated to need more memory than this, MiB (default: half the machine's memory)");
  add_backend_options(*cmd, args->backend);
  cmd->callback([args, &action] { action = [args] { return run_job_file(*args); }; });
}

}  // namespace texwarp::cli
