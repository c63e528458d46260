// The image warp (inverse map per output pixel, then sampling): see image_warp.hpp.
#include "texwarp/core/image_warp.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <utility>

#include "texwarp/core/closed_form_warp.hpp"
#include "texwarp/core/footprint_sampler.hpp"
#include "texwarp/core/image_buffer.hpp"
#include "texwarp/core/parallel_chunks.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

constexpr int kMaxChannels = 16;

// The source as sampled: with a transparent border and no alpha, an alpha channel of 1 is appended.
Image with_coverage(const Image& source) {
  Image out = blank_image(source.width, source.height, source.channels + 1, source.channels);
  const std::size_t n = static_cast<std::size_t>(source.width) * source.height;
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < source.channels; ++c) out.pixels[i * out.channels + c] = source.pixels[i * source.channels + c];
    out.pixels[i * out.channels + source.channels] = 1.0f;
  }
  return out;
}

// S⁻¹ of a closed-form warp when it moves every pixel centre onto a pixel centre (a translation by whole pixels,
// the identity included): (dx, dy) with S⁻¹(p) = p + (dx, dy) exactly. nullopt otherwise.
std::optional<std::pair<int, int>> whole_pixel_translation(const WarpProblem& problem) {
  const Similarity inverse = problem.prealignment().inverse();
  const double tx = inverse.b.real();
  const double ty = inverse.b.imag();
  if (inverse.a.real() != 1.0 || inverse.a.imag() != 0.0 || tx != std::floor(tx) || ty != std::floor(ty) ||
      std::abs(tx) > 1e8 || std::abs(ty) > 1e8) {
    return std::nullopt;
  }
  return std::pair{static_cast<int>(tx), static_cast<int>(ty)};
}

// resample_image at the positions p + (dx, dy) of whole_pixel_translation, value for value: both interpolations
// weigh a pixel centre's own pixel by exactly 1 and its neighbours by exactly 0, so inside the source the sample is
// the pixel itself (+ 0.0f: the sampler's sum turns −0 into +0); outside, the sampler decides as before.
Image translated_image(const Image& source, int dx, int dy, int width, int height, Interpolation interpolation,
                       Border border) {
  const bool coverage = border == Border::kTransparent && source.alpha_channel < 0;
  const int c = source.channels;
  Image out = blank_image(width, height, coverage ? c + 1 : c, coverage ? c : source.alpha_channel);
  std::optional<Image> covered;  // the source with coverage alpha, for the pixels outside it only
  for (int y = 0; y < height; ++y) {
    const int sy = y + dy;
    for (int x = 0; x < width; ++x) {
      const int sx = x + dx;
      float* to = out.pixel(x, y);
      if (sx >= 0 && sx < source.width && sy >= 0 && sy < source.height) {
        const float* from = source.pixel(sx, sy);
        for (int ch = 0; ch < c; ++ch) to[ch] = from[ch] + 0.0f;
        if (coverage) to[c] = 1.0f;
      } else {
        if (coverage && !covered) covered = with_coverage(source);
        sample_image(coverage ? *covered : source, Point(sx + 0.5, sy + 0.5), interpolation, border, to);
      }
    }
  }
  return out;
}

}  // namespace

Image resample_image(Image source, const std::vector<Point>& positions, int width, int height,
                     const SamplingOptions& sampling, const TextureEncoding& encoding, const RunControl& control,
                     ResampleStats* stats) {
  if (positions.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw std::invalid_argument("resample_image: positions do not match the output size");
  }
  // What is filtered: the source itself (or its copy with a coverage channel, the source then released), decoded in
  // place for the role.
  TextureDecodeStats decode_stats;
  const bool coverage = sampling.border == Border::kTransparent && source.alpha_channel < 0;
  Image from = coverage ? with_coverage(source) : std::move(source);
  if (coverage) source = Image();
  decode_texture(from, encoding, control, decode_stats);
  const bool footprint = sampling.filter == SamplingFilter::kFootprint;
  const FootprintSampler sampler(from, sampling.interpolation, sampling.border);
  Image out = blank_image(width, height, from.channels, from.alpha_channel);
  std::atomic<std::size_t> filtered{0};
  for_each_row_band(height, control, [&](int y0, int y1) {
    std::size_t local = 0;
    for (int y = y0; y < y1; ++y) {
      for (int x = 0; x < width; ++x) {
        const Point p = positions[static_cast<std::size_t>(y) * width + x];
        if (footprint) {
          if (sampler.sample(p, grid_jacobian(positions, width, height, x, y), out.pixel(x, y))) ++local;
        } else {
          sample_image(from, p, sampling.interpolation, sampling.border, out.pixel(x, y));
        }
      }
    }
    filtered += local;
  });
  encode_texture(out, encoding, positions, control);
  if (stats) {
    stats->footprint_pixels = filtered.load();
    stats->pyramid_levels = sampler.pyramid_levels();
    stats->pyramid_bytes = sampler.pyramid_bytes();
    stats->repaired_normals = decode_stats.repaired_normals;
  }
  return out;
}

namespace {

void check_warp_input(int source_width, int source_height, int channels, const ImageWarpOptions& options) {
  if (source_width <= 0 || source_height <= 0 || channels <= 0) throw InputError({}, "image is empty");
  if (channels >= kMaxChannels) {
    throw InputError({}, "image has " + std::to_string(channels) + " channels; at most " +
                             std::to_string(kMaxChannels - 1) + " are supported");
  }
  if (options.width < 0 || options.height < 0) throw InputError({}, "output width and height must be positive");
  if (!options.exact && !(options.tolerance_px > 0.0 && std::isfinite(options.tolerance_px))) {
    throw InputError({}, "the warp's tolerance must be a finite number > 0");
  }
}

}  // namespace

OutputGridMap map_output_grid(WarpBackend& backend, const WarpProblem& problem, int source_width, int source_height,
                              const ImageWarpOptions& options, bool positions_needed, const RunControl& control,
                              bool exact_certificate) {
  check_warp_input(source_width, source_height, 1, options);
  OutputGridMap map;
  map.width = options.width > 0 ? options.width : source_width;
  map.height = options.height > 0 ? options.height : source_height;
  CertifiedGridOptions grid_options;
  grid_options.tolerance_px = options.tolerance_px;
  grid_options.samples = options.certificate_samples;
  const auto start = std::chrono::steady_clock::now();
  if (has_closed_form(problem)) {
    // No pathline to integrate: the backend (and its device) is not used.
    map.whole_pixel_shift = whole_pixel_translation(problem);
    if (!map.whole_pixel_shift || positions_needed) {
      map.positions = closed_form_inverse_map_grid(problem, map.width, map.height);
    }
    map.certificate = closed_form_certificate(problem, options.tolerance_px);
    if (control.progress) control.progress(1.0);
  } else if (options.exact) {
    map.positions = backend.inverse_map_grid(problem, map.width, map.height, control);
    if (exact_certificate) {
      map.certificate = exact_grid_certificate(backend, problem, map.width, map.height, grid_options, control);
    }
  } else {
    map.positions =
        certified_inverse_map_grid(backend, problem, map.width, map.height, grid_options, control, map.certificate);
  }
  map.map_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return map;
}

Image sample_output_grid(const OutputGridMap& map, Image source, const ImageWarpOptions& options,
                         const RunControl& control, ImageWarpTimes* times) {
  check_warp_input(source.width, source.height, source.channels, options);
  const auto start = std::chrono::steady_clock::now();
  const bool copies_values = options.encoding.role != ImageRole::kNormal;  // a normal map's repair needs its pass
  ResampleStats sampled;
  Image out;
  if (map.whole_pixel_shift && copies_values) {
    // Every output pixel is a source pixel: copied, not interpolated; colour is copied in its own encoding, which
    // decoding and encoding back would only round.
    out = translated_image(source, map.whole_pixel_shift->first, map.whole_pixel_shift->second, map.width, map.height,
                           options.interpolation, options.border);
  } else {
    if (map.positions.empty()) throw std::logic_error("sample_output_grid: the grid was mapped without positions");
    out = resample_image(std::move(source), map.positions, map.width, map.height,
                         SamplingOptions{options.interpolation, options.border, options.filter}, options.encoding,
                         control, &sampled);
  }
  if (times) {
    times->sampling = sampled;
    times->sampling_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return out;
}

Image warp_image(WarpBackend& backend, const WarpProblem& problem, Image source, const ImageWarpOptions& options,
                 const RunControl& control, WarpCertificate* certificate, ImageWarpTimes* times) {
  check_warp_input(source.width, source.height, source.channels, options);
  const bool positions_needed = options.encoding.role == ImageRole::kNormal;
  OutputGridMap map = map_output_grid(backend, problem, source.width, source.height, options, positions_needed, control,
                                      certificate != nullptr);
  if (certificate) *certificate = map.certificate;
  Image out = sample_output_grid(map, std::move(source), options, control, times);
  if (times) times->map_s = map.map_s;
  return out;
}

}  // namespace texwarp
