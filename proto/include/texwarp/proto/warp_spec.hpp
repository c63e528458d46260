// WarpSpec: the warp part of a job as it travels (the CLI's feature file, later the job's "warp" object).
// Coordinates in pixels (DESIGN.md §3): sources in the input image, targets in the output image.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "texwarp/proto/enum_names.hpp"
#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

// A local frame of the texture at a feature: rotation of its u axis from +x (degrees, towards +y, i.e.
// clockwise on screen since y points down) and uniform scale.
struct FrameSpec {
  double angle_deg = 0.0;
  double scale = 1.0;
  friend TEXWARP_API bool operator==(const FrameSpec&, const FrameSpec&);
};

struct FeatureSpec {
  std::string id;  // optional in the file; empty when absent
  std::array<double, 2> source{};
  std::array<double, 2> target{};
  std::optional<FrameSpec> source_frame;  // both frames present: a gradient feature
  std::optional<FrameSpec> target_frame;
  friend TEXWARP_API bool operator==(const FeatureSpec&, const FeatureSpec&);
};

// Pre-alignment (the paper's Section 3.3): a least-squares similarity of the sources onto the targets, or none.
enum class Prealign { kSimilarity, kNone };

template <>
struct EnumNames<Prealign> {
  static constexpr std::array<std::pair<Prealign, const char*>, 2> kTable = {
      {{Prealign::kSimilarity, "similarity"}, {Prealign::kNone, "none"}}};
};

struct WarpSpec {
  double alpha = 2.0;
  Prealign prealign = Prealign::kSimilarity;
  double tolerance_px = 0.01;
  bool mirror = false;  // flip the texture horizontally first (sources x → width − x), then warp
  std::vector<FeatureSpec> features;
  friend TEXWARP_API bool operator==(const WarpSpec&, const WarpSpec&);
};

}  // namespace texwarp::proto
