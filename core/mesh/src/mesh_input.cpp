// OBJ and JSON mesh input: see mesh_input.hpp.
#include "texwarp/mesh/mesh_input.hpp"

#include <cctype>

#include <tiny_obj_loader.h>

#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::mesh {
namespace {

std::string lower_extension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

int read_index(const nlohmann::json& value, const std::string& path) {
  if (!value.is_number_integer()) {
    throw InputError(path, "expected a vertex index (an integer), got " + proto::json_type_name(value));
  }
  const long long v = value.get<long long>();
  if (v < 0 || v > 0x7fffffffLL) throw InputError(path, "vertex index " + std::to_string(v) + " is out of range");
  return static_cast<int>(v);
}

}  // namespace

TriangleMesh parse_obj_mesh(std::string_view text, const std::string& name) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // face ids must stay those of the file's f lines
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  // ParseFromString ignores mtllib lines: nothing else is opened on behalf of the file.
  if (!reader.ParseFromString(std::string(text), "", config)) {
    std::string error = reader.Error();
    while (!error.empty() && (error.back() == '\n' || error.back() == '\r')) error.pop_back();
    throw InputError(name, "not a valid OBJ file: " + (error.empty() ? std::string("parse error") : error));
  }
  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  TriangleMesh mesh;
  mesh.vertices.reserve(attrib.vertices.size() / 3);
  for (std::size_t i = 0; i + 2 < attrib.vertices.size(); i += 3) {
    mesh.vertices.push_back({static_cast<double>(attrib.vertices[i]), static_cast<double>(attrib.vertices[i + 1]),
                             static_cast<double>(attrib.vertices[i + 2])});
  }
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    std::size_t offset = 0;
    for (const unsigned char count : shape.mesh.num_face_vertices) {
      if (count != 3) {
        throw InputError(name, "face " + std::to_string(mesh.faces.size()) + " has " + std::to_string(count) +
                                   " vertices: only triangles are supported (triangulate the mesh first)");
      }
      Face face{};
      for (std::size_t k = 0; k < 3; ++k) face[k] = shape.mesh.indices[offset + k].vertex_index;
      mesh.faces.push_back(face);
      offset += count;
    }
  }
  return mesh;
}

TriangleMesh decode_mesh_json(const nlohmann::json& value, const std::string& path) {
  proto::JsonReader r(value, path);
  TriangleMesh mesh;
  const nlohmann::json& vertices = r.at("vertices");
  const std::string vpath = r.key_path("vertices");
  if (!vertices.is_array()) throw InputError(vpath, "expected an array of [x, y, z], got " + proto::json_type_name(vertices));
  mesh.vertices.reserve(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const std::string p = proto::json_index_path(vpath, i);
    const nlohmann::json& v = vertices[i];
    if (!v.is_array() || v.size() != 3) throw InputError(p, "expected a point [x, y, z] (an array of 3 numbers)");
    mesh.vertices.push_back({proto::read_finite_number(v[0], proto::json_index_path(p, 0)),
                             proto::read_finite_number(v[1], proto::json_index_path(p, 1)),
                             proto::read_finite_number(v[2], proto::json_index_path(p, 2))});
  }
  const nlohmann::json& triangles = r.at("triangles");
  const std::string tpath = r.key_path("triangles");
  if (!triangles.is_array()) {
    throw InputError(tpath, "expected an array of [a, b, c], got " + proto::json_type_name(triangles));
  }
  mesh.faces.reserve(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const std::string p = proto::json_index_path(tpath, i);
    const nlohmann::json& t = triangles[i];
    if (!t.is_array() || t.size() != 3) {
      throw InputError(p, "expected a triangle [a, b, c] (an array of 3 vertex indices)");
    }
    mesh.faces.push_back({read_index(t[0], proto::json_index_path(p, 0)), read_index(t[1], proto::json_index_path(p, 1)),
                          read_index(t[2], proto::json_index_path(p, 2))});
  }
  r.reject_unknown_keys();
  return mesh;
}

TriangleMesh read_mesh_file(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext != "obj" && ext != "json") {
    throw InputError(path, "unknown mesh format: expected a .obj or .json file");
  }
  const std::string text = read_text_file(path, kMaxMeshFileBytes);
  TriangleMesh mesh;
  if (ext == "obj") {
    mesh = parse_obj_mesh(text, path);
  } else {
    const nlohmann::json j = proto::parse_json(text, path);
    try {
      mesh = decode_mesh_json(j, "$");
    } catch (const InputError& e) {
      throw InputError(path + ": " + e.where(), e.detail());
    }
  }
  validate_mesh(mesh, MeshSource{path, ext == "json" ? "$" : ""});
  return mesh;
}

}  // namespace texwarp::mesh
