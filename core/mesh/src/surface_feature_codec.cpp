// The map-mesh feature file decoder: see surface_feature_codec.hpp.
#include "texwarp/mesh/surface_feature_codec.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::mesh {
namespace {

using proto::json_index_path;
using proto::json_type_name;
using proto::JsonReader;

Vec3 read_vec3(const nlohmann::json& value, const std::string& path) {
  if (!value.is_array() || value.size() != 3) {
    throw InputError(path, "expected [x, y, z] (an array of 3 numbers), got " +
                               (value.is_array() ? "an array of " + std::to_string(value.size()) + " items"
                                                 : json_type_name(value)));
  }
  return {proto::read_finite_number(value[0], json_index_path(path, 0)),
          proto::read_finite_number(value[1], json_index_path(path, 1)),
          proto::read_finite_number(value[2], json_index_path(path, 2))};
}

int read_id(JsonReader& r, std::string_view key) {
  const auto v = r.optional_integer(key);
  if (*v < 0 || *v > 0x7fffffffLL) {
    throw InputError(r.key_path(key), "expected a 0-based id, got " + std::to_string(*v));
  }
  return static_cast<int>(*v);
}

SurfaceTarget decode_target(const nlohmann::json& value, const std::string& path) {
  JsonReader r(value, path);
  r.know_keys({"barycentric"});
  const int kinds = int(r.has("face")) + int(r.has("point")) + int(r.has("vertex"));
  if (kinds != 1) {
    throw InputError(path, kinds == 0 ? "expected a surface target: {\"face\", \"barycentric\"}, {\"point\"} or {\"vertex\"}"
                                      : "give exactly one of \"face\", \"point\" or \"vertex\"");
  }
  SurfaceTarget target;
  if (r.has("face")) {
    FaceTarget t;
    t.face = read_id(r, "face");
    const nlohmann::json& w = r.at("barycentric");
    const std::string wpath = r.key_path("barycentric");
    const Vec3 b = read_vec3(w, wpath);
    const double sum = b.x + b.y + b.z;
    if (std::min({b.x, b.y, b.z}) < -kBarycentricSlack || std::abs(sum - 1.0) > kBarycentricSlack) {
      throw InputError(wpath, "barycentric weights must be ≥ 0 and sum to 1 (got sum " + std::to_string(sum) + ")");
    }
    Barycentric c{std::max(b.x, 0.0), std::max(b.y, 0.0), std::max(b.z, 0.0)};
    const double s = c[0] + c[1] + c[2];
    for (double& x : c) x /= s;
    t.barycentric = c;
    target = t;
  } else if (r.has("point")) {
    target = PointTarget{read_vec3(r.at("point"), r.key_path("point"))};
  } else {
    target = VertexTarget{read_id(r, "vertex")};
  }
  r.reject_unknown_keys();
  return target;
}

Frame decode_source_frame(const nlohmann::json& value, const std::string& path) {
  return frame_from_spec(proto::decode_frame_spec(value, path));
}

SurfaceFrame decode_target_frame(const nlohmann::json& value, const std::string& path) {
  JsonReader r(value, path);
  SurfaceFrame frame;
  frame.direction = read_vec3(r.at("direction"), r.key_path("direction"));
  if (!(norm(frame.direction) > 0.0)) throw InputError(r.key_path("direction"), "the direction must not be zero");
  frame.texels_per_unit = r.number("texels_per_unit");
  if (frame.texels_per_unit <= 0.0) {
    throw InputError(r.key_path("texels_per_unit"), "must be > 0, got " + std::to_string(frame.texels_per_unit));
  }
  r.reject_unknown_keys();
  return frame;
}

SurfaceFeature decode_feature(const nlohmann::json& value, const std::string& path) {
  JsonReader r(value, path);
  SurfaceFeature f;
  if (auto id = r.optional_string("id")) f.id = *id;
  const auto source = proto::read_point(r.at("source"), r.key_path("source"));
  f.source = Point(source[0], source[1]);
  f.target = decode_target(r.at("target"), r.key_path("target"));
  if (r.has("source_frame")) f.source_frame = decode_source_frame(r.at("source_frame"), r.key_path("source_frame"));
  if (r.has("target_frame")) f.target_frame = decode_target_frame(r.at("target_frame"), r.key_path("target_frame"));
  if (f.source_frame.has_value() != f.target_frame.has_value()) {
    throw InputError(path, "a gradient feature needs both source_frame and target_frame (only " +
                               std::string(f.source_frame ? "source_frame" : "target_frame") + " given)");
  }
  r.reject_unknown_keys();
  return f;
}

}  // namespace

SurfaceFeatureSet decode_surface_features(const nlohmann::json& value, const std::string& path) {
  JsonReader r(value, path);
  SurfaceFeatureSet set;
  if (auto a = r.optional_number("alpha")) set.options.alpha = *a;
  if (auto p = r.optional_string("prealign")) {
    if (*p == "similarity") {
      set.options.prealign = Prealign::kSimilarity;
    } else if (*p == "none") {
      set.options.prealign = Prealign::kNone;
    } else {
      throw InputError(r.key_path("prealign"), "expected \"similarity\" or \"none\", got \"" + *p + "\"");
    }
  }
  if (auto t = r.optional_number("tolerance_px")) set.options.tolerance_px = *t;
  if (auto s = r.optional_number("snap_tolerance")) {
    if (*s < 0.0) throw InputError(r.key_path("snap_tolerance"), "must be ≥ 0, got " + std::to_string(*s));
    set.snap_tolerance = *s;
  }
  const nlohmann::json& features = r.at("features");
  const std::string fpath = r.key_path("features");
  if (!features.is_array()) throw InputError(fpath, "expected an array, got " + json_type_name(features));
  for (std::size_t i = 0; i < features.size(); ++i) {
    set.features.push_back(decode_feature(features[i], json_index_path(fpath, i)));
  }
  r.reject_unknown_keys();
  return set;
}

}  // namespace texwarp::mesh
