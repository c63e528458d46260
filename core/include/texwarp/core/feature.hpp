// Feature: one constraint of the warp, positional (source → target) or gradient (with a frame at each end).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp {

// Orientation of the texture's u axis (radians from +x towards +y) and uniform scale at a feature.
struct Frame {
  double angle_rad = 0.0;
  double scale = 1.0;
};

struct Feature {
  std::string id{};                     // for messages; may be empty
  Point source{};                       // pixels in the source image
  Point target{};                       // pixels in the output image
  std::optional<Frame> source_frame{};  // both set: a gradient feature (Eq. 4)
  std::optional<Frame> target_frame{};

  bool is_gradient() const { return source_frame.has_value() && target_frame.has_value(); }
};

// "features[3] (\"nose\")": how messages name a feature.
std::string describe_feature(const std::vector<Feature>& features, std::size_t index);

}  // namespace texwarp
