// Steps shared by the image and the mesh job's runs: see job_steps.hpp.
#include "job_steps.hpp"

#include <algorithm>

#include "input_place.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/map_pipeline.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/sampling_report.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/core/texture_file.hpp"
#include "texwarp/core/udim_texture.hpp"
#include "texwarp/core/warp_certificate_json.hpp"
#include "texwarp/proto/job_report_codec.hpp"

namespace texwarp::runner {

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

RunControl phase(const RunControl& control, double lo, double hi) {
  RunControl c = control;
  if (control.progress) {
    c.progress = [progress = control.progress, lo, hi](double f) {
      progress(lo + (hi - lo) * std::clamp(f, 0.0, 1.0));
    };
  }
  return c;
}

void report_progress(const RunControl& control, double fraction) {
  if (control.canceled()) throw CanceledError();
  if (control.progress) control.progress(fraction);
}

Image read_texture(const PlannedMap& map, Border border, const JobLimits& limits, const RunControl& control) {
  return at_path(map.where, [&] {
    if (map.udim) return read_udim_canvas(*map.udim, border, limits.image, control);
    return read_image(map.texture_file, limits.image, nullptr, control);
  });
}

JobFile write_warped_image(const JobPlan& plan, const PlannedMap& map, const Image& warped,
                           const std::filesystem::path& path, proto::StageTimings& stages,
                           proto::OutputImageReport* output) {
  ImageEncoding encoding;
  encoding.png_compression_level = plan.spec->output.png_compression_level;
  encoding.compression = plan.spec->output.compression;
  ImageWriteTimes times;
  const WrittenImage written = write_output_image(path.string(), warped, map.output_format, encoding,
                                                  plan.spec->output.texture, texture_color_space(map.encoding), &times);
  record_written(written, times, stages, output);
  return {map.image_file, media_type_for(map.image_file), map.encoding.role};
}

std::vector<JobFile> write_warped_tiles(const JobPlan& plan, const PlannedMap& map, const Image& warped,
                                        const std::filesystem::path& out_dir, StagedFiles& staged,
                                        proto::StageTimings& stages, proto::OutputImageReport* output) {
  ImageEncoding encoding;
  encoding.png_compression_level = plan.spec->output.png_compression_level;
  encoding.compression = plan.spec->output.compression;
  ImageWriteTimes times;
  const WrittenImage written = write_udim_tiles(
      (out_dir / map.image_file).string(), warped, *map.udim, staged, [&](const std::string& path, const Image& tile) {
        ImageWriteTimes one;
        const WrittenImage w = write_output_image(path, tile, map.output_format, encoding, plan.spec->output.texture,
                                                  texture_color_space(map.encoding), &one);
        times.encode_s += one.encode_s;
        times.write_s += one.write_s;
        return w;
      });
  record_written(written, times, stages, output);
  std::vector<JobFile> files;
  for (const UdimTile& t : map.udim->tiles) {
    const std::string name = udim_tile_path(map.image_file, t.number);
    files.push_back({name, media_type_for(name), map.encoding.role});
  }
  return files;
}

namespace {

// A map's input and output sections; the output's pixel format and channels are what the file holds
// (write_warped_image), known once it is written.
proto::MapReport map_sections(const JobPlan& plan, const PlannedMap& map, const Image& warped) {
  proto::MapReport r;
  r.name = map.name;
  r.input = {map.header.width, map.header.height, map.header.channels, map.header.format};
  r.output.file = map.image_file;
  r.output.width = warped.width;
  r.output.height = warped.height;
  r.output.channels = warped.channels;
  r.output.interpolation = plan.spec->output.interpolation;
  r.output.border = plan.spec->output.border;
  return r;
}

}  // namespace

bool positions_needed(const JobPlan& plan) {
  return std::any_of(plan.maps.begin(), plan.maps.end(),
                     [](const PlannedMap& m) { return m.encoding.role == ImageRole::kNormal; });
}

WarpedMaps warp_maps(const JobPlan& plan, const OutputGridMap& grid, const ImageWarpOptions& options, bool mirror,
                     const std::filesystem::path& out_dir, const JobLimits& limits, const RunControl& control,
                     proto::StageTimings& stages) {
  WarpedMaps result;
  StagedFiles staged;
  const std::size_t n = plan.maps.size();
  const auto count = static_cast<double>(n);
  // Per map, filled by the steps (a write on its own thread touches its map's entries alone: its files, its
  // report's output and its own stage timings, merged below).
  std::vector<proto::MapReport> reports(n);
  std::vector<std::vector<JobFile>> files(n);
  std::vector<proto::StageTimings> write_stages(n);
  MapPipelineSteps steps;
  steps.decode = [&](std::size_t i) {
    report_progress(control, static_cast<double>(i) / count);  // a canceled job stops before the next map
    const PlannedMap& map = plan.maps[i];
    std::optional<double> read;
    Image source = timed(read, [&] {
      Image texture = read_texture(map, options.border, limits, control);  // a canceled job stops within a band
      if (mirror) mirror_image(texture);
      return texture;
    });
    stages.add(proto::LatencyStage::kDecode, *read);
    reports[i].read_s = *read;
    return source;
  };
  steps.sample = [&](std::size_t i, Image source) {
    const PlannedMap& map = plan.maps[i];
    ImageWarpOptions map_options = options;
    map_options.encoding = map.encoding;
    ImageWarpTimes times;
    Image warped =
        sample_output_grid(grid, std::move(source), map_options,
                           phase(control, static_cast<double>(i) / count, static_cast<double>(i + 1) / count), &times);
    stages.add(proto::LatencyStage::kSampling, times.sampling_s);
    const double read_s = reports[i].read_s;
    reports[i] = map_sections(plan, map, warped);
    reports[i].read_s = read_s;
    reports[i].sampling_s = times.sampling_s;
    reports[i].output.sampling = sampling_report(map_options, times.sampling);
    return warped;
  };
  steps.write = [&](std::size_t i, const Image& warped) {
    const PlannedMap& map = plan.maps[i];
    std::optional<double> write;
    timed(write, [&] {
      if (map.udim) {
        files[i] = write_warped_tiles(plan, map, warped, out_dir, staged, write_stages[i], &reports[i].output);
        return;
      }
      const std::filesystem::path to =
          n > 1 ? std::filesystem::path(staged.stage((out_dir / map.image_file).string())) : out_dir / map.image_file;
      files[i].push_back(write_warped_image(plan, map, warped, to, write_stages[i], &reports[i].output));
    });
    reports[i].write_s = *write;
  };
  const std::vector<double> waited = run_map_pipeline(n, steps);
  for (std::size_t i = 0; i < n; ++i) {
    // The report's stages count what the job waited for: of each write, the part the next map's decode did not hide.
    const double shown = waited_share(reports[i].write_s, waited[i]);
    for (const proto::LatencyStage s : {proto::LatencyStage::kEncode, proto::LatencyStage::kWrite}) {
      if (const auto seconds = write_stages[i][s]) stages.add(s, *seconds * shown);
    }
    result.read_s += reports[i].read_s;
    result.sampling_s += reports[i].sampling_s;
    result.write_s += reports[i].write_s;
    for (JobFile& f : files[i]) result.files.push_back(std::move(f));
    result.reports.push_back(std::move(reports[i]));
  }
  report_progress(control, 1.0);
  staged.publish_all();
  return result;
}

void record_written(const WrittenImage& written, const ImageWriteTimes& times, proto::StageTimings& stages,
                    proto::OutputImageReport* output) {
  if (output) {
    output->pixel_format = written.format;
    output->channels = written.channels;
  }
  stages.add(proto::LatencyStage::kEncode, times.encode_s);
  stages.add(proto::LatencyStage::kWrite, times.write_s);
}

void record_warp(proto::JobReport& report, const WarpCertificate& certificate, bool closed_form) {
  report.method = closed_form         ? proto::WarpMethodReport::kClosedForm
                  : certificate.exact ? proto::WarpMethodReport::kPerPixel
                                      : proto::WarpMethodReport::kCertifiedLattice;
  report.certificate = certificate_report(certificate);
}

JobOutput finish_job(const std::filesystem::path& out_dir, std::vector<JobFile> files, proto::JobReport report,
                     Clock::time_point start, const RunControl& control) {
  report.timings.total_s = seconds_since(start);
  report.files.clear();
  for (const auto& f : files) report.files.push_back(f.name);
  report.files.emplace_back(kReportFile);
  write_text_file_atomically((out_dir / kReportFile).string(), proto::encode_job_report(report).dump(2) + "\n");
  files.push_back({kReportFile, media_type_for(kReportFile)});
  report_progress(control, 1.0);
  return {std::move(files), std::move(report)};
}

}  // namespace texwarp::runner
