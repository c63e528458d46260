// The stages of a command's or a job's latency budget, named once here (in the order they run): the CLI's
// `--timings`, the report's timings.stages and the weights of `--progress` all use this one list.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <utility>

#include "texwarp/proto/enum_names.hpp"
#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

enum class LatencyStage {
  kStartup,      // process start to main's first line: loading and relocating the libraries (CLI only)
  kPlan,         // parsing the job or features (a mesh job: its mesh and region), the image header, the problem
  kDeviceSetup,  // opening the compute device and building (or loading) its kernels
  kDecode,       // decoding the source texture
  kMapping,      // mesh: LSCM, feature placement, the vertices' inverse map, UV quality
  kPathlines,    // the inverse map of the output pixels (lattice or per-pixel pathlines; the closed form)
  kSampling,     // resampling the source at the mapped positions
  kVerify,       // constraint residuals and the Jacobian check
  kEncode,       // the image encoder writing the output (compression)
  kWrite,        // flushing the output files to disk and putting them in place, the report
};

template <>
struct EnumNames<LatencyStage> {
  static constexpr std::array<std::pair<LatencyStage, const char*>, 10> kTable{{
      {LatencyStage::kStartup, "startup"},
      {LatencyStage::kPlan, "plan"},
      {LatencyStage::kDeviceSetup, "device_setup"},
      {LatencyStage::kDecode, "decode"},
      {LatencyStage::kMapping, "mapping"},
      {LatencyStage::kPathlines, "pathlines"},
      {LatencyStage::kSampling, "sampling"},
      {LatencyStage::kVerify, "verify"},
      {LatencyStage::kEncode, "encode"},
      {LatencyStage::kWrite, "write"},
  }};
};

inline constexpr std::size_t kLatencyStageCount = EnumNames<LatencyStage>::kTable.size();

// Seconds per stage; a stage that did not happen is absent. Stages do not overlap, so their sum is at most the
// wall time they were measured in.
struct StageTimings {
  std::array<std::optional<double>, kLatencyStageCount> seconds{};

  static constexpr std::size_t index(LatencyStage stage) { return static_cast<std::size_t>(stage); }
  std::optional<double> operator[](LatencyStage stage) const { return seconds[index(stage)]; }
  // Adds `s` to the stage (a stage may run in several pieces).
  void add(LatencyStage stage, double s) {
    auto& slot = seconds[index(stage)];
    slot = slot.value_or(0.0) + s;
  }
  double sum() const {
    double total = 0.0;
    for (const auto& s : seconds) total += s.value_or(0.0);
    return total;
  }
  TEXWARP_API bool operator==(const StageTimings&) const;
};

}  // namespace texwarp::proto
