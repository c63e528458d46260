// A command's latency budget and progress (--timings, --progress): stages timed as they run (proto::LatencyStage),
// startup measured from the process's start (/proc/self/stat), and 'progress N%' lines on stderr from a ticker
// thread at least every 0.5 s, each stage weighted by its predicted seconds (runner/stage_costs.hpp), monotone,
// 100 % only when the command is done.
#pragma once

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "texwarp/proto/latency_stage.hpp"
#include "texwarp/runner/stage_costs.hpp"

namespace texwarp::cli {

// Adds --timings[=table|json] (the budget on stderr at the end) to `command`; `mode` is "" when not given.
void add_timings_option(CLI::App& command, std::string& mode);
// Adds --progress (CommandClock's 'progress N%' lines on stderr) to `command`.
void add_progress_option(CLI::App& command, bool& progress);

// Seconds from this process's start (the kernel's start time in /proc/self/stat) to now; 0 when unknown.
double seconds_since_process_start();

class CommandClock {
 public:
  // `stages`: the stages the command will run, in order; their weights in the progress are their predicted
  // seconds (runner::predicted_seconds) for the default workload until set_workload, startup's its measured
  // seconds. `progress`: print progress lines.
  CommandClock(std::vector<proto::LatencyStage> stages, bool progress);
  ~CommandClock();
  CommandClock(const CommandClock&) = delete;
  CommandClock& operator=(const CommandClock&) = delete;

  // f() timed as `stage`: the progress moves to the stage's start, then to its end.
  template <class F>
  decltype(auto) time(proto::LatencyStage stage, F&& f) {
    begin(stage);
    const auto start = std::chrono::steady_clock::now();
    if constexpr (std::is_void_v<decltype(f())>) {
      f();
      end(stage, start);
    } else {
      decltype(auto) result = f();
      end(stage, start);
      return result;
    }
  }

  // The command's work is known (after its plan): the stages are weighted by their predicted seconds for it.
  // The progress never goes back: a stage already passed keeps the share it had.
  void set_workload(const runner::StageWorkload& work);

  // Time measured elsewhere, added to `stage` (which counts as done).
  void add(proto::LatencyStage stage, double seconds);
  // Time added to `stage` without moving the progress: work that reports it through progress_until.
  void record(proto::LatencyStage stage, double seconds);
  // The progress within `stage` (0..1): a RunControl progress callback, from any thread.
  std::function<void(double)> progress_within(proto::LatencyStage stage);
  // The progress (0..1) from where it stands now to the end of `stage`: work whose stages interleave (a texture
  // set's maps, each decoded, sampled, encoded and written in turn) moving it as a whole.
  std::function<void(double)> progress_until(proto::LatencyStage stage);
  // The progress (0..1) of the command's work after startup, as that work reports it (texwarp run: the job's).
  void set_fraction(double fraction);

  // The command is done: progress 100 %, the ticker stops, and with `mode` the budget on stderr.
  void finish(const std::string& mode);

  const proto::StageTimings& stages() const { return stages_; }

 private:
  void begin(proto::LatencyStage stage);
  void end(proto::LatencyStage stage, std::chrono::steady_clock::time_point start);
  double start_of(proto::LatencyStage stage) const;   // the progress fraction where `stage` begins
  double weight_of(proto::LatencyStage stage) const;  // its share
  void advance(double fraction);                      // monotone, below 1 until finish
  void weigh(const runner::StageWorkload& work);
  void tick();

  std::vector<proto::LatencyStage> order_;
  std::vector<double> weights_;  // normalised, by position in order_
  proto::StageTimings stages_;
  bool progress_;
  std::mutex mutex_;
  std::condition_variable wake_;
  double fraction_ = 0.0;
  int printed_ = -1;
  std::chrono::steady_clock::time_point printed_at_;
  bool done_ = false;
  std::thread ticker_;
};

}  // namespace texwarp::cli
