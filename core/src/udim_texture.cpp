// UDIM textures: see udim_texture.hpp.
#include "texwarp/core/udim_texture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <utility>

#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

std::string size_text(const ImageHeader& h) {
  return std::to_string(h.width) + "×" + std::to_string(h.height) + ", " + std::to_string(h.channels) + " channels, " +
         proto::to_string(h.format);
}

}  // namespace

bool has_udim_token(const std::string& path) { return path.find(kUdimToken) != std::string::npos; }

std::string udim_tile_path(const std::string& pattern, int tile) {
  std::string out = pattern;
  const auto at = out.find(kUdimToken);
  if (at != std::string::npos) out.replace(at, std::string(kUdimToken).size(), std::to_string(tile));
  return out;
}

ImageHeader UdimCanvas::header(bool transparent_missing) const {
  ImageHeader h = tile;
  h.width = columns * tile.width;
  h.height = rows * tile.height;
  if (transparent_missing && missing_tiles() && h.alpha_channel < 0) {
    h.alpha_channel = h.channels;
    h.channels += 1;
  }
  h.decoder_whole_image_bytes = tile.decoder_whole_image_bytes;
  return h;
}

UdimCanvas find_udim_tiles(const std::string& pattern, const InputLocation& where, const ImageLimits& limits,
                           const UdimTileLookup& lookup) {
  UdimCanvas canvas;
  canvas.pattern = pattern;
  for (int n = kFirstUdimTile; n <= kLastUdimTile; ++n) {
    std::optional<std::string> file;
    if (lookup) {
      file = lookup(n);
    } else {
      std::error_code ec;
      const std::string path = udim_tile_path(pattern, n);
      if (std::filesystem::is_regular_file(path, ec)) file = path;
    }
    if (file) canvas.tiles.push_back({n, *file});
  }
  if (canvas.tiles.empty()) {
    throw InputError(where, "\"" + pattern + "\" matches no UDIM tile: no file for any of " +
                                std::to_string(kFirstUdimTile) + "–" + std::to_string(kLastUdimTile));
  }
  ImageLimits tile_limits = limits;
  for (const UdimTile& t : canvas.tiles) {
    const ImageHeader h = read_image_header(t.file, tile_limits);
    if (&t == &canvas.tiles.front()) {
      canvas.tile = h;
    } else if (h.width != canvas.tile.width || h.height != canvas.tile.height || h.channels != canvas.tile.channels ||
               h.alpha_channel != canvas.tile.alpha_channel) {
      throw InputError(where, "the tiles of \"" + pattern + "\" differ: tile " + std::to_string(t.number) + " is " +
                                  size_text(h) + ", tile " + std::to_string(canvas.tiles.front().number) + " " +
                                  size_text(canvas.tile) + " (every tile of a UDIM texture must be alike)");
    }
    canvas.columns = std::max(canvas.columns, t.u() + 1);
    canvas.rows = std::max(canvas.rows, t.v() + 1);
  }
  const ImageHeader whole = canvas.header(true);
  check_image_size(whole.width, whole.height,
                   pattern + " (its canvas of " + std::to_string(canvas.columns) + "×" + std::to_string(canvas.rows) +
                       " tiles)",
                   limits);
  return canvas;
}

Image read_udim_canvas(const UdimCanvas& canvas, Border border, const ImageLimits& limits, const RunControl& control) {
  const bool transparent = border == Border::kTransparent;
  const ImageHeader h = canvas.header(transparent);
  Image out(h.width, h.height, h.channels, h.alpha_channel);
  const bool coverage = h.channels > canvas.tile.channels;  // missing tiles: an alpha channel, 0 there
  std::vector<char> present(static_cast<std::size_t>(canvas.columns) * canvas.rows, 0);
  for (const UdimTile& t : canvas.tiles) {
    const Image tile = read_image(t.file, limits, nullptr, control);
    const int x0 = canvas.x_of(t);
    const int y0 = canvas.y_of(t);
    present[static_cast<std::size_t>(t.v()) * canvas.columns + t.u()] = 1;
    for (int y = 0; y < tile.height; ++y) {
      for (int x = 0; x < tile.width; ++x) {
        const float* from = tile.pixel(x, y);
        float* to = out.pixel(x0 + x, y0 + y);
        std::copy(from, from + tile.channels, to);
        if (coverage) to[tile.channels] = 1.0f;
      }
    }
  }
  if (transparent || !canvas.missing_tiles()) return out;
  // Clamp or repeat: a missing tile's pixel copies the nearest texel of a tile that exists. That texel lies in a tile
  // no further (in tile units) than the nearest tile plus the missing tile's diagonal: only those are searched.
  const int tw = canvas.tile.width;
  const int th = canvas.tile.height;
  const auto gap = [](int a0, int a1, int b) { return b < a0 ? a0 - b : (b > a1 ? b - a1 : 0); };
  for (int v = 0; v < canvas.rows; ++v) {
    for (int u = 0; u < canvas.columns; ++u) {
      if (present[static_cast<std::size_t>(v) * canvas.columns + u] != 0) continue;
      std::vector<std::pair<double, const UdimTile*>> near;
      for (const UdimTile& t : canvas.tiles) {
        const double du = std::max(std::abs(t.u() - u) - 1, 0) * static_cast<double>(tw);
        const double dv = std::max(std::abs(t.v() - v) - 1, 0) * static_cast<double>(th);
        near.emplace_back(std::hypot(du, dv), &t);
      }
      const double reach = std::min_element(near.begin(), near.end())->first + std::hypot(tw, th);
      std::vector<const UdimTile*> candidates;
      for (const auto& [distance, tile] : near) {
        if (distance <= reach) candidates.push_back(tile);
      }
      const int x0 = u * tw;
      const int y0 = (canvas.rows - 1 - v) * th;
      for (int y = y0; y < y0 + th; ++y) {
        for (int x = x0; x < x0 + tw; ++x) {
          long long best = -1;
          int bx = 0;
          int by = 0;
          for (const UdimTile* t : candidates) {  // by tile number: ties go to the lower
            const int tx = canvas.x_of(*t);
            const int ty = canvas.y_of(*t);
            const long long gx = gap(tx, tx + tw - 1, x);
            const long long gy = gap(ty, ty + th - 1, y);
            const long long d = gx * gx + gy * gy;
            if (best < 0 || d < best) {
              best = d;
              bx = std::clamp(x, tx, tx + tw - 1);
              by = std::clamp(y, ty, ty + th - 1);
            }
          }
          std::copy(out.pixel(bx, by), out.pixel(bx, by) + out.channels, out.pixel(x, y));
        }
      }
    }
  }
  return out;
}

WrittenImage write_udim_tiles(const std::string& output_pattern, const Image& image, const UdimCanvas& canvas,
                              StagedFiles& staged, const UdimTileWriter& write) {
  WrittenImage written;
  for (const UdimTile& t : canvas.tiles) {
    Image tile(canvas.tile.width, canvas.tile.height, image.channels, image.alpha_channel);
    const int x0 = canvas.x_of(t);
    const int y0 = canvas.y_of(t);
    for (int y = 0; y < tile.height; ++y) {
      const float* from = image.pixel(x0, y0 + y);
      std::copy(from, from + static_cast<std::size_t>(tile.width) * image.channels, tile.pixel(0, y));
    }
    written = write(staged.stage(udim_tile_path(output_pattern, t.number)), tile);
  }
  return written;
}

}  // namespace texwarp
