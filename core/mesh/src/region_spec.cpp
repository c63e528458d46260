// Region file decoding and region selection: see region_spec.hpp.
#include "texwarp/mesh/region_spec.hpp"

#include <unordered_map>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::mesh {
namespace {

int read_id(const nlohmann::json& value, const std::string& path) {
  if (!value.is_number_integer()) throw InputError(path, "expected an id (an integer), got " + proto::json_type_name(value));
  const long long id = value.get<long long>();
  if (id < 0 || id > 0x7fffffffLL) throw InputError(path, "id " + std::to_string(id) + " is out of range (ids are 0-based)");
  return static_cast<int>(id);
}

std::vector<int> read_ids(const nlohmann::json& value, const std::string& path) {
  if (!value.is_array()) throw InputError(path, "expected an array of ids, got " + proto::json_type_name(value));
  std::vector<int> ids;
  ids.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) ids.push_back(read_id(value[i], proto::json_index_path(path, i)));
  return ids;
}

}  // namespace

RegionSpec decode_region_spec(const nlohmann::json& value, const std::string& path) {
  proto::JsonReader r(value, path);
  RegionSpec spec;
  const bool has_faces = r.has("faces");
  const bool has_boundary = r.has("boundary");
  if (has_faces == has_boundary) {
    throw InputError(r.path(), has_faces ? "give either \"faces\" or \"boundary\", not both"
                                         : "expected \"faces\": [f, ...] or \"boundary\": [v, ...] with \"seed_face\"");
  }
  if (has_faces) {
    spec.faces = read_ids(r.at("faces"), r.key_path("faces"));
    if (spec.faces.empty()) throw InputError(r.key_path("faces"), "the face list is empty");
    std::unordered_map<int, std::size_t> seen;
    for (std::size_t i = 0; i < spec.faces.size(); ++i) {
      const auto [it, inserted] = seen.emplace(spec.faces[i], i);
      if (!inserted) {
        throw InputError(proto::json_index_path(r.key_path("faces"), i),
                         "face " + std::to_string(spec.faces[i]) + " is listed twice (also at [" +
                             std::to_string(it->second) + "])");
      }
    }
    if (r.has("seed_face")) throw InputError(r.key_path("seed_face"), "seed_face goes with \"boundary\", not \"faces\"");
  } else {
    spec.boundary = read_ids(r.at("boundary"), r.key_path("boundary"));
    if (spec.boundary.empty()) throw InputError(r.key_path("boundary"), "the boundary curve is empty");
    spec.seed_face = read_id(r.at("seed_face"), r.key_path("seed_face"));
  }
  r.reject_unknown_keys();
  return spec;
}

MeshRegion select_region(const TriangleMesh& mesh, const std::optional<RegionSpec>& spec, const std::string& where) {
  if (!spec) return whole_mesh_region(mesh, where);
  const std::string prefix = where.empty() ? std::string() : where + ": ";
  if (!spec->is_curve()) {
    for (std::size_t i = 0; i < spec->faces.size(); ++i) {
      if (spec->faces[i] >= mesh.face_count()) {
        throw InputError(prefix + "$.faces[" + std::to_string(i) + "]",
                         "face " + std::to_string(spec->faces[i]) + " does not exist (the mesh has " +
                             std::to_string(mesh.face_count()) + " faces)");
      }
    }
    return disk_region(mesh, spec->faces, where);
  }
  for (std::size_t i = 0; i < spec->boundary.size(); ++i) {
    if (spec->boundary[i] >= mesh.vertex_count()) {
      throw InputError(prefix + "$.boundary[" + std::to_string(i) + "]",
                       "vertex " + std::to_string(spec->boundary[i]) + " does not exist (the mesh has " +
                           std::to_string(mesh.vertex_count()) + " vertices)");
    }
  }
  if (spec->seed_face >= mesh.face_count()) {
    throw InputError(prefix + "$.seed_face", "face " + std::to_string(spec->seed_face) +
                                                 " does not exist (the mesh has " + std::to_string(mesh.face_count()) +
                                                 " faces)");
  }
  const std::vector<int> curve = close_vertex_curve(mesh, spec->boundary, where);
  return disk_region(mesh, faces_inside_curve(mesh, curve, spec->seed_face, where), where);
}

}  // namespace texwarp::mesh
