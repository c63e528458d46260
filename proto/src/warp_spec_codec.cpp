// JSON codec for the warp spec: see warp_spec_codec.hpp.
#include "texwarp/proto/warp_spec_codec.hpp"

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {
namespace {

FeatureSpec decode_feature(const nlohmann::json& value, const std::string& path) {
  JsonReader r(value, path);
  FeatureSpec f;
  if (auto id = r.optional_string("id")) f.id = *id;
  f.source = read_point(r.at("source"), r.key_path("source"));
  f.target = read_point(r.at("target"), r.key_path("target"));
  if (r.has("source_frame")) f.source_frame = decode_frame_spec(r.at("source_frame"), r.key_path("source_frame"));
  if (r.has("target_frame")) f.target_frame = decode_frame_spec(r.at("target_frame"), r.key_path("target_frame"));
  if (f.source_frame.has_value() != f.target_frame.has_value()) {
    throw InputError(path, "a gradient feature needs both source_frame and target_frame (only " +
                               std::string(f.source_frame ? "source_frame" : "target_frame") + " given)");
  }
  r.reject_unknown_keys();
  return f;
}

nlohmann::json encode_frame(const FrameSpec& frame) {
  return {{"angle_deg", frame.angle_deg}, {"scale", frame.scale}};
}

}  // namespace

FrameSpec decode_frame_spec(const nlohmann::json& value, const std::string& path) {
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

const char* to_string(PrealignSpec prealign) {
  return prealign == PrealignSpec::kSimilarity ? "similarity" : "none";
}

WarpSpec decode_warp_spec(const nlohmann::json& value, const std::string& path) {
  JsonReader r(value, path);
  WarpSpec spec;
  if (auto a = r.optional_number("alpha")) spec.alpha = *a;
  if (auto p = r.optional_string("prealign")) {
    if (*p == "similarity") {
      spec.prealign = PrealignSpec::kSimilarity;
    } else if (*p == "none") {
      spec.prealign = PrealignSpec::kNone;
    } else {
      throw InputError(r.key_path("prealign"), "expected \"similarity\" or \"none\", got \"" + *p + "\"");
    }
  }
  if (auto t = r.optional_number("tolerance_px")) spec.tolerance_px = *t;
  const auto& features = r.at("features");
  const std::string features_path = r.key_path("features");
  if (!features.is_array()) throw InputError(features_path, "expected an array, got " + json_type_name(features));
  spec.features.reserve(features.size());
  for (std::size_t i = 0; i < features.size(); ++i) {
    spec.features.push_back(decode_feature(features[i], json_index_path(features_path, i)));
  }
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
    if (f.source_frame) j["source_frame"] = encode_frame(*f.source_frame);
    if (f.target_frame) j["target_frame"] = encode_frame(*f.target_frame);
    features.push_back(std::move(j));
  }
  return {{"alpha", spec.alpha},
          {"prealign", to_string(spec.prealign)},
          {"tolerance_px", spec.tolerance_px},
          {"features", std::move(features)}};
}

std::vector<std::array<double, 2>> decode_points(const nlohmann::json& value, const std::string& path) {
  if (!value.is_array()) throw InputError(path, "expected an array of points [[x, y], ...], got " + json_type_name(value));
  std::vector<std::array<double, 2>> points;
  points.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) points.push_back(read_point(value[i], json_index_path(path, i)));
  return points;
}

nlohmann::json encode_points(const std::vector<std::array<double, 2>>& points) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& p : points) out.push_back({p[0], p[1]});
  return out;
}

}  // namespace texwarp::proto
