// proto::WarpSpec → core features and options: see feature_conversion.hpp.
#include "texwarp/core/feature_conversion.hpp"

#include <numbers>

namespace texwarp {
Frame frame_from_spec(const proto::FrameSpec& f) { return {f.angle_deg * std::numbers::pi / 180.0, f.scale}; }

std::vector<Feature> features_from_spec(const proto::WarpSpec& spec) {
  std::vector<Feature> out;
  out.reserve(spec.features.size());
  for (const auto& f : spec.features) {
    Feature g;
    g.id = f.id;
    g.source = Point(f.source[0], f.source[1]);
    g.target = Point(f.target[0], f.target[1]);
    if (f.source_frame) g.source_frame = frame_from_spec(*f.source_frame);
    if (f.target_frame) g.target_frame = frame_from_spec(*f.target_frame);
    out.push_back(std::move(g));
  }
  return out;
}

WarpOptions options_from_spec(const proto::WarpSpec& spec) {
  WarpOptions o;
  o.alpha = spec.alpha;
  o.prealign = spec.prealign;
  o.tolerance_px = spec.tolerance_px;
  return o;
}

}  // namespace texwarp
