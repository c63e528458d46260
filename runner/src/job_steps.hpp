// Steps shared by the image and the mesh job's runs: timing, progress phases, reading the planned texture,
// writing the warped image and, last, report.json.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <type_traits>
#include <vector>

#include "job_plan.hpp"
#include "texwarp/core/atomic_file.hpp"
#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/image.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/job_report.hpp"
#include "texwarp/runner/job_runner.hpp"

namespace texwarp::runner {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start);

// f(), its duration stored in `seconds` (a phase of the report's timings).
template <class F>
decltype(auto) timed(std::optional<double>& seconds, F&& f) {
  const auto start = Clock::now();
  if constexpr (std::is_void_v<decltype(f())>) {
    f();
    seconds = seconds_since(start);
  } else {
    decltype(auto) result = f();
    seconds = seconds_since(start);
    return result;
  }
}

// A RunControl whose progress fractions land in [lo, hi] of the caller's.
RunControl phase(const RunControl& control, double lo, double hi);

// Progress `fraction`; CanceledError when the job is canceled.
void report_progress(const RunControl& control, double fraction);

// A map's pixels (InputError at its place in the job, never naming the file); CanceledError within a band of rows once
// the job is canceled.
Image read_texture(const PlannedMap& map, Border border, const JobLimits& limits, const RunControl& control);

// Writes `warped`, the map's output, to `path` (its image file in the output folder, or that file's staging path) in
// its output format and compression; the entry names the image file and the map's role. Its encode and write stages
// go into `stages`; the pixel format and channels the file holds (write_image's answer) into `output` if given.
JobFile write_warped_image(const JobPlan& plan, const PlannedMap& map, const Image& warped,
                           const std::filesystem::path& path, proto::StageTimings& stages,
                           proto::OutputImageReport* output = nullptr);

// Writes `warped`, a UDIM map's canvas, as its tiles (udim_tile_path of its image file in `out_dir`) through
// `staged`; an entry per tile.
std::vector<JobFile> write_warped_tiles(const JobPlan& plan, const PlannedMap& map, const Image& warped,
                                        const std::filesystem::path& out_dir, StagedFiles& staged,
                                        proto::StageTimings& stages, proto::OutputImageReport* output = nullptr);

// The job's maps (plan.maps) sampled through one output grid's map, one after another: each read (mirrored with
// `mirror`), sampled with its role and `options` (the output's size, filter, border; the map's encoding replaces its
// role) and written, so that only one map's pixels are held beside the grid. A set's files (and a UDIM map's tiles)
// are staged and appear together once every map is written. Progress 0 → 1 over the maps through `control`.
struct WarpedMaps {
  std::vector<proto::MapReport> reports;  // per map, in the job's order
  std::vector<JobFile> files;
  double read_s = 0.0;
  double sampling_s = 0.0;
  double write_s = 0.0;
};
WarpedMaps warp_maps(const JobPlan& plan, const OutputGridMap& grid, const ImageWarpOptions& options, bool mirror,
                     const std::filesystem::path& out_dir, const JobLimits& limits, const RunControl& control,
                     proto::StageTimings& stages);

// Whether a map of the plan samples the grid's positions even where the others are copied by whole pixels (a normal
// map): map_output_grid's `positions_needed`.
bool positions_needed(const JobPlan& plan);

// A written image's pixel format and channels into `output` (if given), its encode and write stages into `stages`.
void record_written(const WrittenImage& written, const ImageWriteTimes& times, proto::StageTimings& stages,
                    proto::OutputImageReport* output);

// The report's method, certificate and exact from what the image warp showed (`closed_form`: the warp took
// closed_form_warp.hpp's path).
void record_warp(proto::JobReport& report, const WarpCertificate& certificate, bool closed_form);

// Completes the report (files, total time since `start`), writes report.json last, reports progress 1 and
// returns the job's output.
JobOutput finish_job(const std::filesystem::path& out_dir, std::vector<JobFile> files, proto::JobReport report,
                     Clock::time_point start, const RunControl& control);

}  // namespace texwarp::runner
