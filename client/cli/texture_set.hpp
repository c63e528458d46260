// The maps of a command's texture set, shared by `warp` (--in) and `map-mesh` (--texture): each [ROLE=]PATH argument's
// header, role and output (--out for one input, --out-dir for any number: each output keeps its input's file name),
// the set's memory against the budget, and the maps warped on one output grid one after another, each but the first
// decoded while the one before it is encoded and written.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <future>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "command_clock.hpp"
#include "texture_flags.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/memory_estimate.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/core/udim_texture.hpp"
#include "texwarp/proto/job_report.hpp"

namespace texwarp::cli {

// One map of the set: its input (a file, or the tiles of a <UDIM> path), header, role and output.
struct SetMap {
  RoleAndPath input;
  std::optional<UdimCanvas> udim;
  ImageHeader header;  // a UDIM texture's: its canvas
  TextureEncoding encoding;
  std::string output;  // empty: the map is not warped (map-mesh without a texture output)
  PixelFormat format = PixelFormat::kUint8;
};

// The command's names for the set's flags and what it allows.
struct SetFlags {
  std::string in = "--in";            // the inputs' flag
  std::string out = "--out";          // one input's output
  std::string out_dir = "--out-dir";  // any number's output folder
  bool udim = true;                   // <UDIM> paths allowed (else refused, naming the input)
  bool output_required = true;        // no output at all is refused (else the maps are only planned)
  std::string resized;                // "--width" or "--height" when given (a UDIM texture is then refused)
};

// The set's maps from its arguments: the limit of proto::kMaxJobImages maps, roles (TextureFlags), UDIM tiles, one
// size for all, outputs (InputError naming the flag: neither or both of out and out_dir, two inputs written as one
// name, an output that would replace its input, a <UDIM> on one side only). `format`: asked for, else each input's.
std::vector<SetMap> plan_set_maps(const std::vector<std::string>& arguments, const std::string& out,
                                  const std::string& out_dir, const std::optional<PixelFormat>& format,
                                  const TextureFlags& texture, Border border, const SetFlags& flags);

// The map PrefetchedSource decodes: the first with an output (maps.end() when none has one).
std::vector<SetMap>::const_iterator prefetched_map(const std::vector<SetMap>& maps);

// The warp of `map`, one of `maps`, as the memory estimate sees it (memory_estimate.hpp), warped to width × height (0:
// the map's own) with `border` and `filter`; the prefetched map's source decoded while the output grid is mapped. The
// positions and anything resident are the caller's to add.
ImageWarpMemoryInput set_map_memory(const std::vector<SetMap>& maps, const SetMap& map, int width, int height,
                                    Border border, SamplingFilter filter);

// The set's largest phase against the budget: each map's warp, and each map decoded while the one before it is
// written (texture_set_overlap_memory). `memory_of` describes a map's warp; InputError at the map's file (with
// `size`, e.g. " (warped to 512×512)", appended) naming `budget_flag`. Returns the estimate with the largest peak.
MemoryEstimate check_set_memory(const std::vector<SetMap>& maps,
                                const std::function<ImageWarpMemoryInput(const SetMap&)>& memory_of,
                                std::uint64_t budget, const std::string& size, const std::string& budget_flag);

// What one map's warp wrote: its report as a mesh job's `maps` holds it (name: the input's file name; output.file:
// the output's path; a UDIM texture's width and height: one tile's), and a line for the terminal.
struct WrittenSetMap {
  proto::MapReport report;
  std::string summary;  // "wrote PATH (W×H, C channels, FORMAT); sampled as …"
};

// How the set's maps are warped and written.
struct SetWarp {
  ImageWarpOptions options;  // the grid's sampling; each map's encoding is its own
  ImageEncoding encoding;
  bool texture_output = false;  // TIFF and EXR as render-ready textures
  bool mirror = false;          // each source flipped horizontally first
  std::string folder;           // the outputs' folder (--out-dir): made if missing, and removed again if the set fails
  RunControl control;
};

// A map's source as its warp reads it: a file, or a UDIM texture's canvas (`border` where a tile is missing);
// flipped horizontally when `mirror`. CanceledError once `control` is cancelled (read_image).
Image decode_set_map(const SetMap& map, Border border, bool mirror, const RunControl& control = {});

// The first map with an output decoded on a thread of its own from the moment this is made, while the command sets
// up its device and maps the output grid (mostly one core's work); warp_set_maps then waits for it instead of
// decoding it. Destroyed unused (the command failed before its maps), it cancels the decode and waits only for the
// band of rows in flight (read_image), not for the rest of the image.
class PrefetchedSource {
 public:
  PrefetchedSource(const std::vector<SetMap>& maps, Border border, bool mirror);
  PrefetchedSource(const PrefetchedSource&) = delete;
  PrefetchedSource& operator=(const PrefetchedSource&) = delete;
  ~PrefetchedSource();
  // The source and the decode's own seconds, once; rethrows the decode's error.
  std::pair<Image, double> take();

 private:
  std::atomic<bool> cancel_{false};  // read by the decode's thread: declared before it, so it outlives it
  std::future<std::pair<Image, double>> decoded_;
};

// The set's outputs checked before its map is computed (output_paths.hpp): `folder` (SetFlags::out_dir) could be
// made, or each single output's folder (each UDIM tile's) exists. std::runtime_error naming the flag (exit 1).
void check_set_outputs(const std::vector<SetMap>& maps, const std::string& folder, const SetFlags& flags);

// The maps with an output, sampled from `grid` in turn and written; with more than one map each file is staged and
// all appear together once every map is written (or none, nor a folder made for them). Decode, sampling, encode and
// write are timed on `clock` (a prefetched first source: the time waited for it), and its progress moves map by map
// to the end of its encode stage.
std::vector<WrittenSetMap> warp_set_maps(const OutputGridMap& grid, const std::vector<SetMap>& maps,
                                         const SetWarp& warp, CommandClock& clock, PrefetchedSource* first = nullptr);

}  // namespace texwarp::cli
