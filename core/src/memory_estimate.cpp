// The memory an image warp will allocate, by phase: see memory_estimate.hpp.
#include "texwarp/core/memory_estimate.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>

#include "texwarp/core/point.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

// The certified lattice (certified_warp.cpp): its grid of positions and, when the lattice would cost more than a
// pathline per pixel, the per-pixel grid that replaces it, both alive at once; and its nodes. Its cost rule
// stops it at about 0.6 nodes per output pixel, each ~100 bytes (hash entry, position, a Jacobian for 3 in 8,
// growth slack): counted at that bound, since the job's features decide how far it refines.
constexpr std::uint64_t kPositionBytes = sizeof(Point);
constexpr std::uint64_t kLatticeNodeBytesPerPixel = 56;

constexpr std::uint64_t kMaxBytes = std::numeric_limits<std::uint64_t>::max();

// Products and sums that saturate instead of wrapping (a 2³¹ × 2³¹ output times 88 bytes does not fit).
std::uint64_t times(std::uint64_t a, std::uint64_t b) { return a != 0 && b > kMaxBytes / a ? kMaxBytes : a * b; }
std::uint64_t plus(std::uint64_t a, std::uint64_t b) { return b > kMaxBytes - a ? kMaxBytes : a + b; }

std::uint64_t pixels(int width, int height) {
  return times(static_cast<std::uint64_t>(std::max(width, 0)), static_cast<std::uint64_t>(std::max(height, 0)));
}

std::string size_text(int width, int height) { return std::to_string(width) + "×" + std::to_string(height); }

std::uint64_t phase_sum(const MemoryPhase& phase) {
  std::uint64_t sum = 0;
  for (const MemoryItem& item : phase) sum = plus(sum, item.bytes);
  return sum;
}

}  // namespace

void MemoryEstimate::add_phase(MemoryPhase phase) {
  std::stable_sort(phase.begin(), phase.end(),
                   [](const MemoryItem& a, const MemoryItem& b) { return a.bytes > b.bytes; });
  phases_.push_back(std::move(phase));
}

std::uint64_t MemoryEstimate::peak_bytes() const { return phase_sum(peak_phase()); }

const MemoryPhase& MemoryEstimate::peak_phase() const {
  static const MemoryPhase kNone;
  const MemoryPhase* best = &kNone;
  for (const MemoryPhase& phase : phases_) {
    if (phase_sum(phase) > phase_sum(*best)) best = &phase;
  }
  return *best;
}

std::string MemoryEstimate::describe() const {
  std::string text = "about " + format_bytes(peak_bytes()) + " (";
  bool first = true;
  for (const MemoryItem& item : peak_phase()) {
    if (item.bytes == 0) continue;
    text += (first ? "" : ", ") + item.what + " " + format_bytes(item.bytes);
    first = false;
  }
  return text + ")";
}

std::uint64_t bytes_per_value(PixelFormat format) {
  switch (format) {
    case PixelFormat::kUint8:
      return 1;
    case PixelFormat::kUint16:
    case PixelFormat::kHalf:
      return 2;
    case PixelFormat::kFloat:
      return 4;
  }
  return 4;
}

std::string describe_channels(int channels, bool alpha) {
  if (channels == 1) return "grey";
  if (channels == 2 && alpha) return "grey+alpha";
  if (channels == 3 && !alpha) return "RGB";
  if (channels == 4 && alpha) return "RGBA";
  return std::to_string(channels) + " channels";
}

namespace {

// The buffers of one image warp that the phases are made of.
struct WarpBuffers {
  std::uint64_t source_pixels = 0;
  std::uint64_t output_pixels = 0;
  bool coverage = false;  // the source gains a coverage channel
  int out_channels = 0;
  MemoryItem source;
  MemoryItem output;
  MemoryItem positions;
  MemoryPhase decoding;  // the source as it is decoded and the decoder's own buffers
  MemoryItem encoder;    // the output converted to the file's pixel format
};

WarpBuffers warp_buffers(const ImageWarpMemoryInput& input) {
  const ImageHeader& s = input.source;
  WarpBuffers b;
  const int width = input.output_width > 0 ? input.output_width : s.width;
  const int height = input.output_height > 0 ? input.output_height : s.height;
  b.source_pixels = pixels(s.width, s.height);
  b.output_pixels = pixels(width, height);
  const bool has_alpha = s.alpha_channel >= 0;
  b.coverage = input.transparent_border && !has_alpha;
  b.out_channels = s.channels + (b.coverage ? 1 : 0);
  const std::string out_kind = describe_channels(b.out_channels, has_alpha || b.coverage);
  b.source = {"source " + size_text(s.width, s.height) + " " + describe_channels(s.channels, has_alpha) + " as float",
              times(b.source_pixels, static_cast<std::uint64_t>(s.channels) * sizeof(float))};
  b.output = {"output " + size_text(width, height) + " " + out_kind + " as float",
              times(b.output_pixels, static_cast<std::uint64_t>(b.out_channels) * sizeof(float))};
  b.positions = {"source positions of " + size_text(width, height) + " output pixels",
                 times(b.output_pixels, kPositionBytes)};
  // Decoding: the source grows band by band; the decoder converts one band at a time (from the whole image it holds
  // throughout, for an interlaced PNG's samples, a progressive JPEG's coefficients, a WebP's or RLE BMP's pixels; from
  // a row of tiles, for a tiled file).
  b.decoding = {b.source, {"decoding buffers", std::min<std::uint64_t>(b.source.bytes, 2 * kImageDecodeChunkBytes)}};
  if (s.decoder_whole_image_bytes > 0) b.decoding.push_back({"held by the decoder", s.decoder_whole_image_bytes});
  b.encoder = {
      "encoder's buffer " + size_text(width, height) + " " + out_kind + " as " + to_string(input.output_format),
      times(b.output_pixels, static_cast<std::uint64_t>(b.out_channels) * bytes_per_value(input.output_format))};
  return b;
}

}  // namespace

MemoryPhase decoding_buffers(const ImageWarpMemoryInput& input) { return warp_buffers(input).decoding; }

MemoryEstimate image_warp_memory(const ImageWarpMemoryInput& input) {
  const WarpBuffers b = warp_buffers(input);
  const std::uint64_t source_pixels = b.source_pixels;
  const std::uint64_t output_pixels = b.output_pixels;
  const bool coverage = b.coverage;
  const int out_channels = b.out_channels;
  const MemoryItem& source = b.source;
  const MemoryItem& output = b.output;
  const MemoryItem& positions = b.positions;
  auto with_resident = [&](MemoryPhase phase) {
    phase.insert(phase.end(), input.resident.begin(), input.resident.end());
    return phase;
  };

  MemoryEstimate estimate;
  estimate.add_phase(with_resident(b.decoding));
  // The inverse map of every output pixel, beside the source (or, decoded meanwhile, the source and its decoder's
  // buffers).
  auto with_source = [&](std::initializer_list<MemoryItem> items) {
    MemoryPhase phase = input.decoded_while_mapped ? b.decoding : MemoryPhase{source};
    phase.insert(phase.end(), items.begin(), items.end());
    return with_resident(std::move(phase));
  };
  switch (input.positions) {
    case PositionMethod::kLattice:
      estimate.add_phase(
          with_source({positions,
                       {"per-pixel fallback of the lattice", times(output_pixels, kPositionBytes)},
                       {"lattice nodes (worst case)", times(output_pixels, kLatticeNodeBytesPerPixel)}}));
      break;
    case PositionMethod::kPerPixel:
      estimate.add_phase(with_source({positions}));
      break;
    case PositionMethod::kBaseline:
      estimate.add_phase(with_source({positions, {"Jacobian check points", times(output_pixels, kPositionBytes)}}));
      break;
  }
  // Resampling: the source (with its coverage channel as a copy), the positions and the output.
  // Resampling: the source (decoded in place for the role) and, while it is made, its copy with a coverage
  // channel; the MIP pyramid, the positions and the output.
  MemoryPhase resampling = {source, positions, output};
  if (coverage) {
    resampling.push_back({"source with coverage alpha as float",
                          times(source_pixels, static_cast<std::uint64_t>(out_channels) * sizeof(float))});
  }
  if (input.pyramid) {
    resampling.push_back({"MIP pyramid (at most a third of the source)",
                          times(source_pixels, static_cast<std::uint64_t>(out_channels) * sizeof(float)) / 3});
  }
  estimate.add_phase(with_resident(std::move(resampling)));
  // Encoding: the output converted to the file's pixel format.
  estimate.add_phase(with_resident({source, output, b.encoder}));
  return estimate;
}

MemoryEstimate texture_set_overlap_memory(const ImageWarpMemoryInput& written, const ImageWarpMemoryInput& decoded) {
  const WarpBuffers w = warp_buffers(written);
  const WarpBuffers d = warp_buffers(decoded);
  MemoryPhase phase = {{"previous map's " + w.output.what, w.output.bytes},
                       {"previous map's " + w.encoder.what, w.encoder.bytes},
                       w.positions};
  for (const MemoryItem& item : d.decoding) phase.push_back(item);
  phase.insert(phase.end(), written.resident.begin(), written.resident.end());
  MemoryEstimate estimate;
  estimate.add_phase(std::move(phase));
  return estimate;
}

void texture_set_phases(std::size_t count, const std::function<ImageWarpMemoryInput(std::size_t)>& memory_of,
                        const std::function<void(const MemoryEstimate&, std::size_t)>& check) {
  for (std::size_t i = 0; i < count; ++i) {
    check(image_warp_memory(memory_of(i)), i);
    if (i > 0) check(texture_set_overlap_memory(memory_of(i - 1), memory_of(i)), i);
  }
}

// The memory limit of this process's control group (cgroup v2 memory.max, else v1 memory.limit_in_bytes), if any:
// in a container it, not the host's RAM, is what the process may use.
std::optional<std::uint64_t> cgroup_memory_limit() {
  for (const char* file : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(file);
    std::string text;
    if (!(in >> text) || text == "max") continue;
    char* end = nullptr;
    const unsigned long long bytes = std::strtoull(text.c_str(), &end, 10);
    if (end != text.c_str() && *end == '\0' && bytes > 0 && bytes < (std::uint64_t{1} << 62)) return bytes;
  }
  return std::nullopt;
}

std::uint64_t default_memory_budget(int concurrent_jobs) {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long page_size = ::sysconf(_SC_PAGE_SIZE);
  std::uint64_t physical = pages > 0 && page_size > 0
                               ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size)
                               : std::uint64_t{4} << 30;
  if (const auto limit = cgroup_memory_limit()) physical = std::min(physical, *limit);
  return physical / 2 / static_cast<std::uint64_t>(std::max(concurrent_jobs, 1));
}

std::uint64_t memory_budget_from_mib(std::uint64_t mib, int concurrent_jobs) {
  return mib == 0 ? default_memory_budget(concurrent_jobs) : times(mib, std::uint64_t{1} << 20);
}

void check_memory_budget(const MemoryEstimate& estimate, std::uint64_t budget_bytes, const InputLocation& where,
                         const std::string& flag) {
  if (budget_bytes == 0 || estimate.peak_bytes() <= budget_bytes) return;
  throw InputError(where, "this job needs " + estimate.describe() + "; the memory limit per job is " +
                              format_bytes(budget_bytes) + " (" + flag + ")");
}

std::string format_bytes(std::uint64_t bytes) {
  static constexpr const char* kUnits[] = {"kB", "MB", "GB", "TB", "PB", "EB"};
  if (bytes < 1000) return std::to_string(bytes) + " bytes";
  auto value = static_cast<double>(bytes);
  int unit = -1;
  while (value >= 999.5 && unit < 5) {
    value /= 1000.0;
    ++unit;
  }
  char text[32];
  std::snprintf(text, sizeof text, value < 9.95 ? "%.1f %s" : "%.0f %s", value, kUnits[unit]);
  return text;
}

}  // namespace texwarp
