// A command's texture set: see texture_set.hpp.
#include "texture_set.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>

#include "output_paths.hpp"
#include "texwarp/core/atomic_file.hpp"
#include "texwarp/core/map_pipeline.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/sampling_report.hpp"
#include "texwarp/core/texture_file.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec.hpp"

namespace texwarp::cli {
namespace {

namespace fs = std::filesystem;

// A map's share of the set's progress once it is decoded and sampled (encoding and writing it the rest).
constexpr double kSampledShare = 0.5;

// The maps' outputs: `out` for one input, else `out_dir` and each input's file name (none: only when no output is
// required). InputError naming the flag when both are given, neither where one is required, two inputs would write
// the same file, or an output would replace its own input.
std::vector<std::string> output_paths(const std::string& out, const std::string& out_dir,
                                      const std::vector<RoleAndPath>& inputs, const SetFlags& flags) {
  if (!out.empty() && !out_dir.empty()) {
    throw InputError(InputLocation::flag(flags.out),
                     "give " + flags.out + " (one input) or " + flags.out_dir + " (any number), not both");
  }
  if (out_dir.empty()) {
    if (out.empty() && flags.output_required) {
      throw InputError(InputLocation::flag(flags.out), "an output is required: " + flags.out + " or " + flags.out_dir);
    }
    if (!out.empty() && inputs.size() > 1) {
      throw InputError(InputLocation::flag(flags.out), std::to_string(inputs.size()) + " inputs (" + flags.in +
                                                           ") write one output each: give " + flags.out_dir +
                                                           " DIR (each output keeps its input's file name)");
    }
    std::vector<std::string> outputs(inputs.size());
    if (!out.empty()) outputs[0] = out;
    return outputs;
  }
  std::vector<std::string> outputs;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const std::string name = fs::path(inputs[i].path).filename().string();
    for (std::size_t j = 0; j < i; ++j) {
      if (fs::path(inputs[j].path).filename().string() == name) {
        throw InputError(InputLocation::flag(flags.in), "\"" + inputs[j].path + "\" and \"" + inputs[i].path +
                                                            "\" would both be written as " + name + " in " +
                                                            flags.out_dir + ": warp them in two commands");
      }
    }
    const fs::path to = fs::path(out_dir) / name;
    std::error_code ec;
    const fs::path folder = fs::path(inputs[i].path).parent_path();
    if (fs::equivalent(out_dir, folder.empty() ? fs::path(".") : folder, ec)) {
      throw InputError(InputLocation::flag(flags.out_dir),
                       to.string() + " is the input itself: give another folder (outputs keep the inputs' names)");
    }
    outputs.push_back(to.string());
  }
  return outputs;
}

}  // namespace

std::vector<SetMap> plan_set_maps(const std::vector<std::string>& arguments, const std::string& out,
                                  const std::string& out_dir, const std::optional<PixelFormat>& format,
                                  const TextureFlags& texture, Border border, const SetFlags& flags) {
  if (arguments.size() > proto::kMaxJobImages) {
    throw InputError(InputLocation::flag(flags.in), std::to_string(arguments.size()) +
                                                        " inputs, more than the limit of " +
                                                        std::to_string(proto::kMaxJobImages) + " maps in one warp");
  }
  std::vector<RoleAndPath> inputs;
  inputs.reserve(arguments.size());
  for (const std::string& in : arguments) inputs.push_back(split_role(in, flags.in));
  const std::vector<std::string> outputs = output_paths(out, out_dir, inputs, flags);
  const std::string out_flag = out_dir.empty() ? flags.out : flags.out_dir;
  std::vector<SetMap> maps;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    SetMap map;
    map.input = inputs[i];
    map.output = outputs[i];
    if (has_udim_token(map.input.path)) {
      if (!flags.udim) {
        throw InputError(InputLocation::flag(flags.in),
                         "\"" + map.input.path +
                             "\" names UDIM tiles: a mesh's warped texture is the region's frame, "
                             "not the texture's canvas, and cannot be cut into tiles (UDIM "
                             "textures are for `texwarp warp`)");
      }
      // The tiles that exist, read as one canvas and written as the same tiles.
      if (!map.output.empty() && !has_udim_token(map.output)) {
        throw InputError(InputLocation::flag(out_flag), "\"" + map.input.path + "\" is a UDIM texture: its output " +
                                                            map.output + " needs the token " + kUdimToken +
                                                            " too (the tiles written)");
      }
      if (!flags.resized.empty()) {
        throw InputError(InputLocation::flag(flags.resized),
                         "a UDIM texture is warped on its canvas and cut into the same tiles: no --width or --height");
      }
      map.udim = find_udim_tiles(map.input.path, InputLocation::flag(flags.in));
      map.header = map.udim->header(border == Border::kTransparent);
      // The role follows the tiles' own header (a missing tile's added alpha says nothing of the colour).
      map.encoding = texture_encoding(map.udim->tile, map.input, texture, flags.in);
    } else {
      if (has_udim_token(map.output)) {
        throw InputError(InputLocation::flag(out_flag), map.output + " has the token " + kUdimToken + " but \"" +
                                                            map.input.path + "\" is one image, not UDIM tiles");
      }
      map.header = read_image_header(map.input.path);
      map.encoding = texture_encoding(map.header, map.input, texture, flags.in);
    }
    map.format = format.value_or(map.header.format);
    if (!maps.empty() && (map.header.width != maps[0].header.width || map.header.height != maps[0].header.height)) {
      throw InputError(InputLocation::flag(flags.in),
                       "the maps of one warp share its pixels: " + map.input.path + " is " +
                           std::to_string(map.header.width) + "×" + std::to_string(map.header.height) + ", " +
                           maps[0].input.path + " " + std::to_string(maps[0].header.width) + "×" +
                           std::to_string(maps[0].header.height));
    }
    maps.push_back(std::move(map));
  }
  return maps;
}

MemoryEstimate check_set_memory(const std::vector<SetMap>& maps,
                                const std::function<ImageWarpMemoryInput(const SetMap&)>& memory_of,
                                std::uint64_t budget, const std::string& size, const std::string& budget_flag) {
  MemoryEstimate largest;
  const auto check = [&](const MemoryEstimate& estimate, const InputLocation& where) {
    check_memory_budget(estimate, budget, where, budget_flag);
    if (estimate.peak_bytes() > largest.peak_bytes()) largest = estimate;
  };
  texture_set_phases(
      maps.size(), [&](std::size_t i) { return memory_of(maps[i]); },
      [&](const MemoryEstimate& estimate, std::size_t i) {
        // The file as the message names it: with the size it is warped to.
        check(estimate, InputLocation::file(maps[i].input.path + size));
      });
  return largest;
}

std::vector<SetMap>::const_iterator prefetched_map(const std::vector<SetMap>& maps) {
  return std::find_if(maps.begin(), maps.end(), [](const SetMap& m) { return !m.output.empty(); });
}

ImageWarpMemoryInput set_map_memory(const std::vector<SetMap>& maps, const SetMap& map, int width, int height,
                                    Border border, SamplingFilter filter) {
  const auto prefetched = prefetched_map(maps);
  ImageWarpMemoryInput memory;
  memory.source = map.header;
  memory.output_width = width;
  memory.output_height = height;
  memory.output_format = map.format;
  memory.transparent_border = border == Border::kTransparent;
  memory.pyramid = filter == SamplingFilter::kFootprint;
  memory.decoded_while_mapped = prefetched != maps.end() && &map == &*prefetched;
  return memory;
}

Image decode_set_map(const SetMap& map, Border border, bool mirror, const RunControl& control) {
  Image image =
      map.udim ? read_udim_canvas(*map.udim, border, {}, control) : read_image(map.input.path, {}, nullptr, control);
  if (mirror) mirror_image(image);
  return image;
}

PrefetchedSource::PrefetchedSource(const std::vector<SetMap>& maps, Border border, bool mirror) {
  const auto first = prefetched_map(maps);
  if (first == maps.end()) return;
  decoded_ = std::async(std::launch::async, [map = &*first, border, mirror, cancel = &cancel_] {
    const auto start = std::chrono::steady_clock::now();
    RunControl control;
    control.cancel = cancel;
    Image image = decode_set_map(*map, border, mirror, control);
    return std::make_pair(std::move(image),
                          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  });
}

PrefetchedSource::~PrefetchedSource() {
  cancel_ = true;
  if (decoded_.valid()) decoded_.wait();  // its CanceledError, or any other, is no longer anyone's
}

std::pair<Image, double> PrefetchedSource::take() { return decoded_.get(); }

void check_set_outputs(const std::vector<SetMap>& maps, const std::string& folder, const SetFlags& flags) {
  if (!folder.empty()) return check_output_folder(flags.out_dir, folder);
  for (const SetMap& m : maps) {
    if (!m.udim) {
      check_output_file(flags.out, m.output);
      continue;
    }
    for (const UdimTile& tile : m.udim->tiles) check_output_file(flags.out, udim_tile_path(m.output, tile.number));
  }
}

std::vector<WrittenSetMap> warp_set_maps(const OutputGridMap& grid, const std::vector<SetMap>& maps,
                                         const SetWarp& warp, CommandClock& clock, PrefetchedSource* first) {
  using proto::LatencyStage;
  std::vector<const SetMap*> to_warp;  // the maps with an output
  for (const SetMap& m : maps) {
    if (!m.output.empty()) to_warp.push_back(&m);
  }
  StagedFiles staged;
  try {
    staged.make_folder(warp.folder);
  } catch (const std::filesystem::filesystem_error& e) {
    throw std::runtime_error("--out-dir " + warp.folder + ": cannot make the folder (" + e.code().message() + ")");
  }
  // Per map, filled by the steps (a write on its own thread touches its map's entries alone).
  std::vector<WrittenSetMap> result(to_warp.size());
  std::vector<ImageWriteTimes> write_times(to_warp.size());
  std::vector<WrittenImage> written(to_warp.size());
  // The stages interleave map by map: their time is recorded as it is measured, and the progress moves by maps to the
  // end of encoding; the write stage is left to putting the files in place and the command's other outputs.
  const std::function<void(double)> progress = clock.progress_until(LatencyStage::kEncode);
  const auto progressed = [&](double maps_done) {
    if (progress) progress(maps_done / static_cast<double>(to_warp.size()));
  };
  MapPipelineSteps steps;
  steps.decode = [&](std::size_t i) {
    const auto start = std::chrono::steady_clock::now();
    const auto since_start = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    };
    if (i == 0 && first) {
      // Decoded meanwhile: the report has the decode's own seconds, the budget the part the command waited for.
      auto [image, seconds] = first->take();
      result[i].report.read_s = seconds;
      clock.record(LatencyStage::kDecode, since_start());
      return std::move(image);
    }
    Image image = decode_set_map(*to_warp[i], warp.options.border, warp.mirror);
    result[i].report.read_s = since_start();
    clock.record(LatencyStage::kDecode, result[i].report.read_s);
    return image;
  };
  steps.sample = [&](std::size_t i, Image source) {
    const SetMap& map = *to_warp[i];
    proto::MapReport& r = result[i].report;
    r.name = fs::path(map.input.path).filename().string();
    r.input = {map.header.width, map.header.height, map.header.channels, map.header.format};
    ImageWarpOptions map_options = warp.options;
    map_options.encoding = map.encoding;
    ImageWarpTimes times;
    Image warped = sample_output_grid(grid, std::move(source), map_options, warp.control, &times);
    clock.record(LatencyStage::kSampling, times.sampling_s);
    r.sampling_s = times.sampling_s;
    r.output.file = map.output;
    r.output.width = map.udim ? map.udim->tile.width : warped.width;
    r.output.height = map.udim ? map.udim->tile.height : warped.height;
    r.output.interpolation = warp.options.interpolation;
    r.output.border = warp.options.border;
    r.output.sampling = sampling_report(map_options, times.sampling);
    progressed(static_cast<double>(i) + kSampledShare);
    return warped;
  };
  steps.write = [&](std::size_t i, const Image& warped) {
    const SetMap& map = *to_warp[i];
    const std::string color_space = texture_color_space(map.encoding);
    const auto write = [&](const std::string& to, const Image& image) {
      ImageWriteTimes one;
      const WrittenImage w =
          write_output_image(to, image, map.format, warp.encoding, warp.texture_output, color_space, &one);
      write_times[i].encode_s += one.encode_s;
      write_times[i].write_s += one.write_s;
      return w;
    };
    const std::string to = map.udim || to_warp.size() == 1 ? map.output : staged.stage(map.output);
    written[i] = map.udim ? write_udim_tiles(map.output, warped, *map.udim, staged, write) : write(to, warped);
    progressed(static_cast<double>(i + 1));
  };
  const std::vector<double> waited = run_map_pipeline(to_warp.size(), steps);
  for (std::size_t i = 0; i < to_warp.size(); ++i) {
    const SetMap& map = *to_warp[i];
    proto::MapReport& r = result[i].report;
    const double worked = write_times[i].encode_s + write_times[i].write_s;
    r.write_s = worked;
    // The budget counts what the command waited for: of the encoding and writing, the part the next map's decode
    // did not hide.
    const double shown = waited_share(worked, waited[i]);
    clock.record(LatencyStage::kEncode, write_times[i].encode_s * shown);
    clock.record(LatencyStage::kWrite, write_times[i].write_s * shown);
    r.output.channels = written[i].channels;
    r.output.pixel_format = written[i].format;
    char line[512];
    std::snprintf(line, sizeof line, "%d×%d, %d channels, %s", r.output.width, r.output.height, written[i].channels,
                  to_string(written[i].format));
    const std::string tiles = map.udim ? std::to_string(map.udim->tiles.size()) + " UDIM tiles of " : "";
    result[i].summary =
        "wrote " + map.output + " (" + tiles + line + "); sampled as " + describe_sampling(*r.output.sampling);
  }
  clock.time(LatencyStage::kWrite, [&] { staged.publish_all(); });
  return result;
}

}  // namespace texwarp::cli
