// Conversion from the wire types (proto::WarpSpec) to the core's features and options.
#pragma once

#include <vector>

#include "texwarp/core/feature.hpp"
#include "texwarp/core/warp_options.hpp"
#include "texwarp/proto/warp_spec.hpp"

namespace texwarp {

Frame frame_from_spec(const proto::FrameSpec& frame);  // degrees → radians
std::vector<Feature> features_from_spec(const proto::WarpSpec& spec);
WarpOptions options_from_spec(const proto::WarpSpec& spec);

}  // namespace texwarp
