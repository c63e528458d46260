// OBJ and JSON mesh input: see mesh_input.hpp.
#include "texwarp/mesh/mesh_input.hpp"

#include <cctype>

#include <tiny_obj_loader.h>

#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"

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

}  // namespace

TriangleMesh parse_obj_mesh(std::string_view text, const InputLocation& where) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // face ids must stay those of the file's f lines
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  // ParseFromString ignores mtllib lines: nothing else is opened on behalf of the file.
  if (!reader.ParseFromString(std::string(text), "", config)) {
    std::string error = reader.Error();
    while (!error.empty() && (error.back() == '\n' || error.back() == '\r')) error.pop_back();
    throw InputError(where, "not a valid OBJ file: " + (error.empty() ? std::string("parse error") : error));
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
        throw InputError(where, "face " + std::to_string(mesh.faces.size()) + " has " + std::to_string(count) +
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

TriangleMesh mesh_from_spec(const proto::MeshDataSpec& spec) {
  TriangleMesh mesh;
  mesh.vertices.reserve(spec.vertices.size());
  for (const auto& v : spec.vertices) mesh.vertices.push_back({v[0], v[1], v[2]});
  mesh.faces.assign(spec.triangles.begin(), spec.triangles.end());
  return mesh;
}

TriangleMesh read_mesh_file(const std::string& path) {
  const InputLocation file = InputLocation::file(path);
  const std::string ext = lower_extension(path);
  if (ext != "obj" && ext != "json") throw InputError(file, "unknown mesh format: expected a .obj or .json file");
  const std::string text = read_text_file(path, kMaxMeshFileBytes);
  TriangleMesh mesh;
  if (ext == "obj") {
    mesh = parse_obj_mesh(text, file);
  } else {
    const nlohmann::json j = proto::parse_json(text, path);
    try {
      mesh = mesh_from_spec(proto::decode_mesh_data(j));
    } catch (const InputError& e) {
      throw InputError(e.where().in_file(path), e.detail());
    }
  }
  validate_mesh(mesh, MeshSource{file, ext == "json" ? std::optional<JsonPath>(JsonPath{}) : std::nullopt});
  return mesh;
}

}  // namespace texwarp::mesh
