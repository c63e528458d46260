// The memory an image warp will allocate, estimated from the source's header and the output's size before any
// pixel is decoded: the buffers alive together in each phase (decoding, the inverse map, resampling, encoding),
// the largest phase's sum as the peak, and the check of that peak against a budget with a message of the numbers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "texwarp/core/image_io.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {

struct MemoryItem {
  std::string what;  // "source 16384×16384 RGBA as float"
  std::uint64_t bytes = 0;
};

// Buffers alive at the same moment.
using MemoryPhase = std::vector<MemoryItem>;

class MemoryEstimate {
 public:
  void add_phase(MemoryPhase phase);
  std::uint64_t peak_bytes() const;       // the largest phase's sum
  const MemoryPhase& peak_phase() const;  // empty when no phase was added
  // "about 4.3 GB (source 16384×16384 RGBA as float 4.3 GB, output 512×512 RGBA as float 4.2 MB, …)": the
  // peak phase's items, largest first.
  std::string describe() const;

 private:
  std::vector<MemoryPhase> phases_;
};

// How an image warp finds each output pixel's source position.
enum class PositionMethod {
  kLattice,   // the certified lattice (certified_warp.hpp), which may give way to a pathline per pixel
  kPerPixel,  // a pathline per output pixel ("exact")
  kBaseline,  // a closed-form baseline (TPS, MLS) and its Jacobian check at every pixel
};

struct ImageWarpMemoryInput {
  ImageHeader source;    // from read_image_header
  int output_width = 0;  // 0: the source's
  int output_height = 0;
  PixelFormat output_format = PixelFormat::kUint8;  // of the written file
  bool transparent_border = true;                   // a source without alpha then gains a coverage channel
  PositionMethod positions = PositionMethod::kLattice;
  bool pyramid = true;                // the footprint filter may build a MIP pyramid (at most a third of the source)
  bool decoded_while_mapped = false;  // the source is decoded while the output grid is mapped (its buffers too)
  MemoryPhase resident;               // alive throughout (a mesh job's mesh and mapping)
};

// Bytes of a stored value of `format`: 1, 2, 2 or 4.
std::uint64_t bytes_per_value(PixelFormat format);

// The phases of reading the source, mapping the output grid, resampling and encoding the output image.
MemoryEstimate image_warp_memory(const ImageWarpMemoryInput& input);

// The source as it is decoded and its decoder's buffers (image_warp_memory's first phase, without `resident`): what
// a decode running beside other work (a mesh's mapping) adds to that work's phase.
MemoryPhase decoding_buffers(const ImageWarpMemoryInput& input);

// A texture set's maps are warped one after another, but each map but the first is decoded while the one before
// it is encoded and written: that phase (the previous map's output and encoder's buffer, the positions, the next
// map's source as it is decoded). `written`'s resident items count once.
MemoryEstimate texture_set_overlap_memory(const ImageWarpMemoryInput& written, const ImageWarpMemoryInput& decoded);

// A texture set's memory phase by phase as run_map_pipeline (map_pipeline.hpp) runs it: each map's warp
// (image_warp_memory) and each map but the first decoded while the one before it is written
// (texture_set_overlap_memory); `check(estimate, i)` is called on each, with the map i it is charged to.
void texture_set_phases(std::size_t count, const std::function<ImageWarpMemoryInput(std::size_t)>& memory_of,
                        const std::function<void(const MemoryEstimate&, std::size_t)>& check);

// The default budget of one job: half the machine's physical memory (or of the control group's memory limit when
// lower, as in a container), shared by `concurrent_jobs` jobs.
std::uint64_t default_memory_budget(int concurrent_jobs);
// A --max-job-memory-mb value (MiB) in bytes; 0: default_memory_budget(concurrent_jobs).
std::uint64_t memory_budget_from_mib(std::uint64_t mib, int concurrent_jobs);

// InputError(where, "this job needs about … (…); the memory limit per job is … (`flag`)") when the estimate's
// peak exceeds budget_bytes (0: no limit).
void check_memory_budget(const MemoryEstimate& estimate, std::uint64_t budget_bytes, const InputLocation& where,
                         const std::string& flag);

// Decimal units with two or three significant digits: "980 bytes", "4.2 MB", "537 MB", "4.3 GB".
std::string format_bytes(std::uint64_t bytes);

// "RGBA", "RGB", "grey+alpha", "grey", or "N channels".
std::string describe_channels(int channels, bool alpha);

}  // namespace texwarp
