// JSON codec for the warp spec: see warp_spec_codec.hpp.
#include "texwarp/proto/warp_spec_codec.hpp"

#include "feature_decoding.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {

FrameSpec decode_frame_spec(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  FrameSpec frame;
  if (auto a = r.optional_number("angle_deg")) frame.angle_deg = *a;
  if (auto s = r.optional_number("scale")) {
    if (*s <= 0.0) throw InputError(r.key_path("scale"), "scale must be > 0, got " + std::to_string(*s));
    frame.scale = *s;
  }
  r.reject_unknown_keys();
  return frame;
}

nlohmann::json encode_frame_spec(const FrameSpec& frame) {
  return {{"angle_deg", frame.angle_deg}, {"scale", frame.scale}};
}

WarpSpec decode_warp_spec(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  WarpSpec spec;
  detail::decode_warp_settings(r, spec);
  if (auto m = r.optional_bool("mirror")) spec.mirror = *m;
  spec.features = detail::decode_feature_list<FeatureSpec>(r, [](const nlohmann::json& v, const JsonPath& p) {
    return detail::decode_feature<FeatureSpec>(v, p, read_point, decode_frame_spec);
  });
  r.reject_unknown_keys();
  return spec;
}

nlohmann::json encode_warp_spec(const WarpSpec& spec) {
  nlohmann::json features = nlohmann::json::array();
  for (const auto& f : spec.features) {
    nlohmann::json j;
    if (!f.id.empty()) j["id"] = f.id;
    j["source"] = {f.source[0], f.source[1]};
    j["target"] = {f.target[0], f.target[1]};
    if (f.source_frame) j["source_frame"] = encode_frame_spec(*f.source_frame);
    if (f.target_frame) j["target_frame"] = encode_frame_spec(*f.target_frame);
    features.push_back(std::move(j));
  }
  nlohmann::json out = {{"alpha", spec.alpha},
                        {"prealign", to_string(spec.prealign)},
                        {"tolerance_px", spec.tolerance_px},
                        {"features", std::move(features)}};
  if (spec.mirror) out["mirror"] = true;
  return out;
}

std::vector<std::array<double, 2>> decode_points(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_array())
    throw InputError(path, "expected an array of points [[x, y], ...], got " + json_type_name(value));
  std::vector<std::array<double, 2>> points;
  points.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) points.push_back(read_point(value[i], path.index(i)));
  return points;
}

nlohmann::json encode_points(const std::vector<std::array<double, 2>>& points) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& p : points) out.push_back({p[0], p[1]});
  return out;
}

}  // namespace texwarp::proto
