// UDIM textures: a path with the token <UDIM> names the tiles 1001–1100 that exist (name.1001.png, …), laid out as
// in UV space: tile 1001 + u + 10·v at column u, row v counting upward. The tiles form one canvas (columns 0…max u,
// rows 0…max v; row v is canvas pixel rows (rows − 1 − v)·tile height onward, y down), which is warped as one image
// (features in canvas pixels) and cut into the same tiles again.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "texwarp/core/atomic_file.hpp"
#include "texwarp/core/image.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/udim_tiles.hpp"

namespace texwarp {

using proto::kFirstUdimTile;
using proto::kLastUdimTile;
using proto::kUdimColumns;
using proto::kUdimToken;

bool has_udim_token(const std::string& path);
// `pattern` with its (first) <UDIM> replaced by the tile's number.
std::string udim_tile_path(const std::string& pattern, int tile);

struct UdimTile {
  int number = kFirstUdimTile;
  std::string file;  // where it is read on this machine
  int u() const { return (number - kFirstUdimTile) % kUdimColumns; }
  int v() const { return (number - kFirstUdimTile) / kUdimColumns; }
};

// The tiles of a UDIM texture that exist, and the canvas they make.
struct UdimCanvas {
  std::string pattern;          // as given, with <UDIM>
  std::vector<UdimTile> tiles;  // by number
  ImageHeader tile;             // every tile's header (they are checked alike)
  int columns = 0;              // u = 0 … columns − 1
  int rows = 0;                 // v = 0 … rows − 1
  bool missing_tiles() const { return static_cast<int>(tiles.size()) < columns * rows; }
  // The canvas's header: columns·tile width × rows·tile height; with `transparent_missing` and tiles missing, an
  // alpha channel is added to a texture without one (missing tiles are transparent).
  ImageHeader header(bool transparent_missing) const;
  // Top-left pixel of a tile in the canvas (y down).
  int x_of(const UdimTile& t) const { return t.u() * tile.width; }
  int y_of(const UdimTile& t) const { return (rows - 1 - t.v()) * tile.height; }
};

// The file of tile `number`, or nullopt when there is none (the default: udim_tile_path, if a regular file).
using UdimTileLookup = std::function<std::optional<std::string>(int number)>;

// Finds the tiles of `pattern` (InputError at `where`: no tile matches; tiles of different sizes, channel counts
// or pixel types, naming the tiles; a canvas beyond the image limits) and reads their headers.
UdimCanvas find_udim_tiles(const std::string& pattern, const InputLocation& where, const ImageLimits& limits = {},
                           const UdimTileLookup& lookup = {});

// The canvas's pixels: every tile at its place; a missing tile reads as the border: transparent (alpha 0, an alpha
// channel added as header(true) says) with Border::kTransparent; with kClamp or kRepeat (which wrap only at the
// canvas's edges) each of its pixels is the nearest texel of a tile that exists (the edge extended, as clamp extends
// the canvas's edges; ties to the lower tile number), so that no black bleeds into the tiles around it.
// CanceledError once `control` is cancelled (read_image's checks, in each tile; not in the missing tiles' fill).
Image read_udim_canvas(const UdimCanvas& canvas, Border border, const ImageLimits& limits = {},
                       const RunControl& control = {});

// Writes one tile's image to a path; returns what the file holds (write_image, write_output_image).
using UdimTileWriter = std::function<WrittenImage(const std::string& path, const Image& tile)>;

// Cuts `image` (the warped canvas, of the canvas's size) into the canvas's tiles and writes each with `write` to the
// staging path (`staged`, put in place together by its publish_all) of udim_tile_path(output_pattern, number).
// Returns what the last file holds.
WrittenImage write_udim_tiles(const std::string& output_pattern, const Image& image, const UdimCanvas& canvas,
                              StagedFiles& staged, const UdimTileWriter& write);

}  // namespace texwarp
