// The one feature decoder, shared by the image warp's features (target: a point in pixels) and the mesh job's
// surface features (target: a place on the surface): id, source, frames and the gradient check are read here.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/warp_spec.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"

namespace texwarp::proto::detail {

// {"id", "source", "target", "source_frame", "target_frame"}: `read_target(value, path)` and
// `read_target_frame(value, path)` decode the two keys whose form depends on the kind of feature.
template <typename FeatureT, typename ReadTarget, typename ReadTargetFrame>
FeatureT decode_feature(const nlohmann::json& value, const JsonPath& path, ReadTarget read_target,
                        ReadTargetFrame read_target_frame) {
  JsonReader r(value, path);
  FeatureT f;
  if (auto id = r.optional_string("id")) f.id = *id;
  f.source = read_point(r.at("source"), r.key_path("source"));
  f.target = read_target(r.at("target"), r.key_path("target"));
  if (r.has("source_frame")) f.source_frame = decode_frame_spec(r.at("source_frame"), r.key_path("source_frame"));
  if (r.has("target_frame")) f.target_frame = read_target_frame(r.at("target_frame"), r.key_path("target_frame"));
  if (f.source_frame.has_value() != f.target_frame.has_value()) {
    throw InputError(path, "a gradient feature needs both source_frame and target_frame (only " +
                               std::string(f.source_frame ? "source_frame" : "target_frame") + " given)");
  }
  r.reject_unknown_keys();
  return f;
}

// The warp's settings every feature file has: "alpha", "prealign", "tolerance_px" (each optional).
template <typename SpecT>
void decode_warp_settings(JsonReader& r, SpecT& spec) {
  if (auto a = r.optional_number("alpha")) spec.alpha = *a;
  if (auto p = r.optional_string("prealign")) spec.prealign = parse_enum<Prealign>(*p, r.key_path("prealign"));
  if (auto t = r.optional_number("tolerance_px")) spec.tolerance_px = *t;
}

// The "features" array, each item decoded by `decode_item(value, path)`.
template <typename ItemT, typename DecodeItem>
std::vector<ItemT> decode_feature_list(JsonReader& r, DecodeItem decode_item) {
  const auto& features = r.at("features");
  const JsonPath features_path = r.key_path("features");
  if (!features.is_array()) throw InputError(features_path, "expected an array, got " + json_type_name(features));
  std::vector<ItemT> items;
  items.reserve(features.size());
  for (std::size_t i = 0; i < features.size(); ++i) items.push_back(decode_item(features[i], features_path.index(i)));
  return items;
}

}  // namespace texwarp::proto::detail
