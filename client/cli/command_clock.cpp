// A command's latency budget and progress: see command_clock.hpp.
#include "command_clock.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <ctime>  // clock_gettime, CLOCK_BOOTTIME (POSIX, declared by glibc's <time.h> under it)
#include <fstream>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

namespace texwarp::cli {
namespace {

using proto::LatencyStage;

constexpr auto kTick = std::chrono::milliseconds(250);  // a line at least every 2 ticks
constexpr auto kMaxSilence = std::chrono::milliseconds(500);

double boot_seconds_now() {
  timespec ts{};
  ::clock_gettime(CLOCK_BOOTTIME, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

}  // namespace

void add_timings_option(CLI::App& command, std::string& mode) {
  command
      .add_flag("--timings{table}", mode,
                "print the command's latency budget by stage on stderr at the end: a table, or --timings=json")
      ->check(CLI::IsMember({"table", "json"}));
}

void add_progress_option(CLI::App& command, bool& progress) {
  command.add_flag("--progress", progress,
                   "print 'progress N%' lines on stderr (at least every 0.5 s, the whole command, 100% at the end)");
}

double seconds_since_process_start() {
  // Field 22 of /proc/self/stat: the start time in clock ticks after boot; the name (field 2) may hold spaces,
  // so fields are counted after its closing parenthesis.
  std::ifstream in("/proc/self/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) return 0.0;
  std::istringstream fields(text.substr(close + 1));
  std::string field;
  for (int i = 3; i <= 22 && fields >> field; ++i) {
    if (i == 22) {
      const auto ticks_per_second = static_cast<double>(::sysconf(_SC_CLK_TCK));
      const double started = std::stod(field) / ticks_per_second;
      return std::max(0.0, boot_seconds_now() - started);
    }
  }
  return 0.0;
}

CommandClock::CommandClock(std::vector<LatencyStage> stages, bool progress)
    : order_(std::move(stages)), progress_(progress) {
  stages_.add(LatencyStage::kStartup, seconds_since_process_start());
  weigh(runner::StageWorkload{});
  if (progress_) {
    printed_at_ = std::chrono::steady_clock::now();
    advance(weight_of(LatencyStage::kStartup));  // startup is done (the first stage; a command may have no plan)
    ticker_ = std::thread([this] { tick(); });
  }
}

CommandClock::~CommandClock() {
  {
    std::lock_guard lock(mutex_);
    done_ = true;
  }
  wake_.notify_all();
  if (ticker_.joinable()) ticker_.join();
}

void CommandClock::weigh(const runner::StageWorkload& work) {
  std::vector<double> seconds;
  double total = 0.0;
  for (const LatencyStage s : order_) {
    // Startup has happened: its own measured time, the others' predicted.
    const std::optional<double> measured = s == LatencyStage::kStartup ? stages_[s] : std::nullopt;
    seconds.push_back(measured ? std::max(*measured, 1e-3) : runner::predicted_seconds(s, work));
    total += seconds.back();
  }
  std::lock_guard lock(mutex_);
  weights_.clear();
  for (const double s : seconds) weights_.push_back(s / total);
}

void CommandClock::set_workload(const runner::StageWorkload& work) {
  weigh(work);
  if (!progress_) return;
  double done = 0.0;  // the stages timed so far
  for (std::size_t i = 0; i < order_.size(); ++i) {
    if (stages_[order_[i]]) done += weights_[i];
  }
  advance(done);
}

double CommandClock::start_of(LatencyStage stage) const {
  double at = 0.0;
  for (std::size_t i = 0; i < order_.size() && order_[i] != stage; ++i) at += weights_[i];
  return std::min(at, 1.0);
}

double CommandClock::weight_of(LatencyStage stage) const {
  for (std::size_t i = 0; i < order_.size(); ++i) {
    if (order_[i] == stage) return weights_[i];
  }
  return 0.0;
}

void CommandClock::begin(LatencyStage stage) {
  if (progress_) advance(start_of(stage));
}

void CommandClock::end(LatencyStage stage, std::chrono::steady_clock::time_point start) {
  stages_.add(stage, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (progress_) advance(start_of(stage) + weight_of(stage));
}

void CommandClock::add(LatencyStage stage, double seconds) {
  stages_.add(stage, seconds);
  if (progress_) advance(start_of(stage) + weight_of(stage));
}

void CommandClock::record(LatencyStage stage, double seconds) { stages_.add(stage, seconds); }

std::function<void(double)> CommandClock::progress_until(LatencyStage stage) {
  if (!progress_) return {};
  double from = 0.0;
  {
    std::lock_guard lock(mutex_);
    from = fraction_;
  }
  const double width = std::max(0.0, start_of(stage) + weight_of(stage) - from);
  return [this, from, width](double f) { advance(from + width * std::clamp(f, 0.0, 1.0)); };
}

std::function<void(double)> CommandClock::progress_within(LatencyStage stage) {
  if (!progress_) return {};
  const double from = start_of(stage);
  const double width = weight_of(stage);
  return [this, from, width](double f) { advance(from + width * std::clamp(f, 0.0, 1.0)); };
}

void CommandClock::set_fraction(double fraction) {
  if (!progress_) return;
  const double started = weight_of(LatencyStage::kStartup);  // done before the work began
  advance(started + (1.0 - started) * std::clamp(fraction, 0.0, 1.0));
}

void CommandClock::advance(double fraction) {
  std::lock_guard lock(mutex_);
  // Monotone, and 100 % is kept for finish: the command is not done while a stage still runs.
  fraction_ = std::max(fraction_, std::min(fraction, 0.99));
  const int percent = static_cast<int>(fraction_ * 100.0);
  if (percent != printed_) {
    printed_ = percent;
    printed_at_ = std::chrono::steady_clock::now();
    std::fprintf(stderr, "progress %d%%\n", percent);
  }
}

void CommandClock::tick() {
  std::unique_lock lock(mutex_);
  while (!done_) {
    wake_.wait_for(lock, kTick);
    if (done_) break;
    if (std::chrono::steady_clock::now() - printed_at_ >= kMaxSilence - kTick / 5) {
      printed_at_ = std::chrono::steady_clock::now();
      std::fprintf(stderr, "progress %d%%\n", printed_);
    }
  }
}

void CommandClock::finish(const std::string& mode) {
  {
    std::lock_guard lock(mutex_);
    done_ = true;
    if (progress_) {
      fraction_ = 1.0;
      std::fprintf(stderr, "progress 100%%\n");
    }
  }
  wake_.notify_all();
  if (ticker_.joinable()) ticker_.join();
  if (mode.empty()) return;
  const double wall = seconds_since_process_start();
  if (mode == "json") {
    nlohmann::json stages = nlohmann::json::object();
    for (const auto& [stage, name] : proto::EnumNames<LatencyStage>::kTable) {
      if (const auto s = stages_[stage]) stages[name] = *s;
    }
    std::fprintf(stderr, "%s\n", nlohmann::json{{"timings", {{"wall_s", wall}, {"stages", stages}}}}.dump().c_str());
    return;
  }
  std::fprintf(stderr, "texwarp: timings (s)\n");
  for (const auto& [stage, name] : proto::EnumNames<LatencyStage>::kTable) {
    if (const auto s = stages_[stage]) {
      std::fprintf(stderr, "  %-13s %8.3f  %5.1f%%\n", name, *s, wall > 0 ? 100.0 * *s / wall : 0.0);
    }
  }
  std::fprintf(stderr, "  %-13s %8.3f  %5.1f%%\n", "other", std::max(0.0, wall - stages_.sum()),
               wall > 0 ? 100.0 * std::max(0.0, wall - stages_.sum()) / wall : 0.0);
  std::fprintf(stderr, "  %-13s %8.3f\n", "wall", wall);
}

}  // namespace texwarp::cli
