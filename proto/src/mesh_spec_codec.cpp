// JSON codecs for a mesh job's parts: see mesh_spec_codec.hpp.
#include "texwarp/proto/mesh_spec_codec.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "feature_decoding.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {
namespace {

constexpr long long kMaxId = 0x7fffffffLL;

std::array<double, 3> read_vec3(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_array() || value.size() != 3) {
    throw InputError(path, "expected [x, y, z] (an array of 3 numbers), got " +
                               (value.is_array() ? "an array of " + std::to_string(value.size()) + " items"
                                                 : json_type_name(value)));
  }
  return {read_finite_number(value[0], path.index(0)), read_finite_number(value[1], path.index(1)),
          read_finite_number(value[2], path.index(2))};
}

nlohmann::json vec3_json(const std::array<double, 3>& v) { return {v[0], v[1], v[2]}; }

// A surface target's "face" / "vertex": a 0-based id.
int read_target_id(JsonReader& r, std::string_view key) {
  const auto v = r.optional_integer(key);
  if (*v < 0 || *v > kMaxId) throw InputError(r.key_path(key), "expected a 0-based id, got " + std::to_string(*v));
  return static_cast<int>(*v);
}

SurfaceTargetSpec decode_surface_target(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  r.know_keys({"barycentric"});
  const int kinds = int(r.has("face")) + int(r.has("point")) + int(r.has("vertex"));
  if (kinds != 1) {
    throw InputError(path, kinds == 0 ? R"(expected a surface target: {"face", "barycentric"}, {"point"} or {"vertex"})"
                                      : R"(give exactly one of "face", "point" or "vertex")");
  }
  SurfaceTargetSpec target;
  if (r.has("face")) {
    FaceTargetSpec t;
    t.face = read_target_id(r, "face");
    const JsonPath wpath = r.key_path("barycentric");
    t.barycentric = read_vec3(r.at("barycentric"), wpath);
    const auto& b = t.barycentric;
    const double sum = b[0] + b[1] + b[2];
    if (std::min({b[0], b[1], b[2]}) < -kBarycentricSlack || std::abs(sum - 1.0) > kBarycentricSlack) {
      throw InputError(wpath, "barycentric weights must be ≥ 0 and sum to 1 (got sum " + std::to_string(sum) + ")");
    }
    target = t;
  } else if (r.has("point")) {
    target = PointTargetSpec{read_vec3(r.at("point"), r.key_path("point"))};
  } else {
    target = VertexTargetSpec{read_target_id(r, "vertex")};
  }
  r.reject_unknown_keys();
  return target;
}

nlohmann::json encode_surface_target(const SurfaceTargetSpec& target) {
  if (const auto* f = std::get_if<FaceTargetSpec>(&target)) {
    return {{"face", f->face}, {"barycentric", vec3_json(f->barycentric)}};
  }
  if (const auto* p = std::get_if<PointTargetSpec>(&target)) return {{"point", vec3_json(p->point)}};
  return {{"vertex", std::get<VertexTargetSpec>(target).vertex}};
}

SurfaceFrameSpec decode_surface_frame(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  SurfaceFrameSpec frame;
  frame.direction = read_vec3(r.at("direction"), r.key_path("direction"));
  const auto& d = frame.direction;
  if (!(std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) > 0.0))
    throw InputError(r.key_path("direction"), "the direction must not be zero");
  frame.texels_per_unit = r.number("texels_per_unit");
  if (frame.texels_per_unit <= 0.0) {
    throw InputError(r.key_path("texels_per_unit"), "must be > 0, got " + std::to_string(frame.texels_per_unit));
  }
  r.reject_unknown_keys();
  return frame;
}

// A region id: a non-negative integer.
int read_region_id(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_number_integer()) throw InputError(path, "expected an id (an integer), got " + json_type_name(value));
  const long long id = value.get<long long>();
  if (id < 0 || id > kMaxId) throw InputError(path, "id " + std::to_string(id) + " is out of range (ids are 0-based)");
  return static_cast<int>(id);
}

std::vector<int> read_region_ids(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_array()) throw InputError(path, "expected an array of ids, got " + json_type_name(value));
  std::vector<int> ids;
  ids.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) ids.push_back(read_region_id(value[i], path.index(i)));
  return ids;
}

int read_vertex_index(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_number_integer()) {
    throw InputError(path, "expected a vertex index (an integer), got " + json_type_name(value));
  }
  const long long v = value.get<long long>();
  if (v < 0 || v > kMaxId) throw InputError(path, "vertex index " + std::to_string(v) + " is out of range");
  return static_cast<int>(v);
}

}  // namespace

SurfaceFeatureSetSpec decode_surface_feature_set(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  SurfaceFeatureSetSpec set;
  detail::decode_warp_settings(r, set);
  if (auto s = r.optional_number("snap_tolerance")) {
    if (*s < 0.0) throw InputError(r.key_path("snap_tolerance"), "must be ≥ 0, got " + std::to_string(*s));
    set.snap_tolerance = *s;
  }
  set.features = detail::decode_feature_list<SurfaceFeatureSpec>(r, [](const nlohmann::json& v, const JsonPath& p) {
    return detail::decode_feature<SurfaceFeatureSpec>(v, p, decode_surface_target, decode_surface_frame);
  });
  r.reject_unknown_keys();
  return set;
}

nlohmann::json encode_surface_feature_set(const SurfaceFeatureSetSpec& spec) {
  nlohmann::json features = nlohmann::json::array();
  for (const auto& f : spec.features) {
    nlohmann::json j;
    if (!f.id.empty()) j["id"] = f.id;
    j["source"] = {f.source[0], f.source[1]};
    j["target"] = encode_surface_target(f.target);
    if (f.source_frame) j["source_frame"] = encode_frame_spec(*f.source_frame);
    if (f.target_frame) {
      j["target_frame"] = {{"direction", vec3_json(f.target_frame->direction)},
                           {"texels_per_unit", f.target_frame->texels_per_unit}};
    }
    features.push_back(std::move(j));
  }
  nlohmann::json out = {{"alpha", spec.alpha},
                        {"prealign", to_string(spec.prealign)},
                        {"tolerance_px", spec.tolerance_px},
                        {"features", std::move(features)}};
  if (spec.snap_tolerance) out["snap_tolerance"] = *spec.snap_tolerance;
  return out;
}

RegionSpec decode_region_spec(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  RegionSpec spec;
  const bool has_faces = r.has("faces");
  const bool has_boundary = r.has("boundary");
  if (has_faces == has_boundary) {
    throw InputError(r.path(), has_faces ? R"(give either "faces" or "boundary", not both)"
                                         : R"(expected "faces": [f, ...] or "boundary": [v, ...] with "seed_face")");
  }
  if (has_faces) {
    spec.faces = read_region_ids(r.at("faces"), r.key_path("faces"));
    if (spec.faces.empty()) throw InputError(r.key_path("faces"), "the face list is empty");
    std::unordered_map<int, std::size_t> seen;
    for (std::size_t i = 0; i < spec.faces.size(); ++i) {
      const auto [it, inserted] = seen.emplace(spec.faces[i], i);
      if (!inserted) {
        throw InputError(r.key_path("faces").index(i), "face " + std::to_string(spec.faces[i]) +
                                                           " is listed twice (also at [" + std::to_string(it->second) +
                                                           "])");
      }
    }
    if (r.has("seed_face")) throw InputError(r.key_path("seed_face"), R"(seed_face goes with "boundary", not "faces")");
  } else {
    spec.boundary = read_region_ids(r.at("boundary"), r.key_path("boundary"));
    if (spec.boundary.empty()) throw InputError(r.key_path("boundary"), "the boundary curve is empty");
    spec.seed_face = read_region_id(r.at("seed_face"), r.key_path("seed_face"));
  }
  r.reject_unknown_keys();
  return spec;
}

nlohmann::json encode_region_spec(const RegionSpec& spec) {
  if (spec.is_curve()) return {{"boundary", spec.boundary}, {"seed_face", spec.seed_face}};
  return {{"faces", spec.faces}};
}

MeshDataSpec decode_mesh_data(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  MeshDataSpec mesh;
  const nlohmann::json& vertices = r.at("vertices");
  const JsonPath vpath = r.key_path("vertices");
  if (!vertices.is_array()) throw InputError(vpath, "expected an array of [x, y, z], got " + json_type_name(vertices));
  mesh.vertices.reserve(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const JsonPath p = vpath.index(i);
    const nlohmann::json& v = vertices[i];
    if (!v.is_array() || v.size() != 3) throw InputError(p, "expected a point [x, y, z] (an array of 3 numbers)");
    mesh.vertices.push_back({read_finite_number(v[0], p.index(0)), read_finite_number(v[1], p.index(1)),
                             read_finite_number(v[2], p.index(2))});
  }
  const nlohmann::json& triangles = r.at("triangles");
  const JsonPath tpath = r.key_path("triangles");
  if (!triangles.is_array()) {
    throw InputError(tpath, "expected an array of [a, b, c], got " + json_type_name(triangles));
  }
  mesh.triangles.reserve(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const JsonPath p = tpath.index(i);
    const nlohmann::json& t = triangles[i];
    if (!t.is_array() || t.size() != 3) {
      throw InputError(p, "expected a triangle [a, b, c] (an array of 3 vertex indices)");
    }
    mesh.triangles.push_back({read_vertex_index(t[0], p.index(0)), read_vertex_index(t[1], p.index(1)),
                              read_vertex_index(t[2], p.index(2))});
  }
  r.reject_unknown_keys();
  return mesh;
}

nlohmann::json encode_mesh_data(const MeshDataSpec& mesh) {
  nlohmann::json vertices = nlohmann::json::array();
  for (const auto& v : mesh.vertices) vertices.push_back(vec3_json(v));
  nlohmann::json triangles = nlohmann::json::array();
  for (const auto& t : mesh.triangles) triangles.push_back({t[0], t[1], t[2]});
  return {{"vertices", std::move(vertices)}, {"triangles", std::move(triangles)}};
}

}  // namespace texwarp::proto
