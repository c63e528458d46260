// OBJ and JSON mesh input: see mesh_input.hpp.
#include "texwarp/mesh/mesh_input.hpp"

#include <cctype>
#include <memory>

#include <tiny_obj_loader.h>

#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/mesh_validation.hpp"
#include "texwarp/mesh/polygon_triangulation.hpp"
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

MeshFile parse_obj_file(std::string_view text, const InputLocation& where) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // triangulated here, each face's triangles kept together
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  // ParseFromString ignores mtllib lines: nothing else is opened on behalf of the file.
  if (!reader.ParseFromString(std::string(text), "", config)) {
    std::string error = reader.Error();
    while (!error.empty() && (error.back() == '\n' || error.back() == '\r')) error.pop_back();
    throw InputError(where, "not a valid OBJ file: " + (error.empty() ? std::string("parse error") : error));
  }
  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  MeshFile file;
  file.format = proto::MeshFormat::kObj;
  file.obj_text = std::string(text);
  TriangleMesh& mesh = file.mesh;
  mesh.vertices.reserve(attrib.vertices.size() / 3);
  for (std::size_t i = 0; i + 2 < attrib.vertices.size(); i += 3) {
    mesh.vertices.push_back({static_cast<double>(attrib.vertices[i]), static_cast<double>(attrib.vertices[i + 1]),
                             static_cast<double>(attrib.vertices[i + 2])});
  }
  file.faces.first_triangle.push_back(0);
  std::vector<int> polygon;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    std::size_t offset = 0;
    for (const unsigned char count : shape.mesh.num_face_vertices) {
      const int face = file.faces.count();
      // tinyobjloader stores a face's vertex count in a byte: a longer face shows as a count that does not add up.
      if (offset + count > shape.mesh.indices.size()) {
        throw InputError(where, "face " + std::to_string(face) + " has more than 255 vertices");
      }
      polygon.clear();
      for (std::size_t k = 0; k < count; ++k) {
        const int v = shape.mesh.indices[offset + k].vertex_index;
        if (v < 0 || v >= mesh.vertex_count()) {
          throw InputError(where, "face " + std::to_string(face) + " uses vertex " + std::to_string(v + 1) +
                                      ", which does not exist (the file has " + std::to_string(mesh.vertex_count()) +
                                      " vertices)");
        }
        polygon.push_back(v);
      }
      offset += count;
      const std::vector<Face> triangles = triangulate_polygon(polygon, mesh.vertices);
      if (triangles.empty()) {
        throw InputError(
            where, "face " + std::to_string(face) + " (" + std::to_string(count) +
                       " vertices) cannot be triangulated: it is degenerate or self-intersecting" +
                       (count > kMaxEarClippingVertices
                            ? ", or not convex with more than " + std::to_string(kMaxEarClippingVertices) + " vertices"
                            : std::string()));
      }
      mesh.faces.insert(mesh.faces.end(), triangles.begin(), triangles.end());
      file.faces.add_face(static_cast<int>(triangles.size()));
    }
    if (offset != shape.mesh.indices.size()) {
      throw InputError(where, "face " + std::to_string(file.faces.count()) + " has more than 255 vertices");
    }
  }
  return file;
}

TriangleMesh parse_obj_mesh(std::string_view text, const InputLocation& where) {
  return parse_obj_file(text, where).mesh;
}

TriangleMesh mesh_from_spec(const proto::MeshDataSpec& spec) {
  TriangleMesh mesh;
  mesh.vertices.reserve(spec.vertices.size());
  for (const auto& v : spec.vertices) mesh.vertices.push_back({v[0], v[1], v[2]});
  mesh.faces.assign(spec.triangles.begin(), spec.triangles.end());
  return mesh;
}

MeshFile parse_mesh_bytes(std::string_view bytes, proto::MeshFormat format, const proto::GltfSelectionSpec& gltf,
                          const InputLocation& where) {
  using proto::MeshFormat;
  if (format == MeshFormat::kObj) return parse_obj_file(bytes, where);
  MeshFile file;
  file.format = format;
  if (format == MeshFormat::kJson) {
    const nlohmann::json j = proto::parse_json(bytes, where.file_name().empty() ? "mesh" : where.file_name());
    file.mesh = mesh_from_spec(proto::decode_mesh_data(j));
  } else {
    auto read = std::make_shared<GltfMesh>(parse_gltf_mesh(bytes, format == MeshFormat::kGlb, gltf, where));
    file.mesh = read->mesh;
    file.gltf = std::move(read);
  }
  file.faces = InputFaces::identity(file.mesh.face_count());
  return file;
}

MeshFile read_mesh_document(const std::string& path, const proto::GltfSelectionSpec& gltf) {
  const InputLocation file = InputLocation::file(path);
  const auto format = proto::enum_from_name<proto::MeshFormat>(lower_extension(path));
  if (!format) throw InputError(file, "unknown mesh format: expected a .obj, .json, .gltf or .glb file");
  const std::string bytes = read_text_file(path, kMaxMeshFileBytes);
  MeshFile mesh;
  try {
    mesh = parse_mesh_bytes(bytes, *format, gltf, file);
  } catch (const InputError& e) {
    if (!e.where().file_name().empty()) throw;
    throw InputError(e.where().in_file(path), e.detail());
  }
  const bool json = *format == proto::MeshFormat::kJson;
  validate_mesh(mesh.mesh, MeshSource{file, json ? std::optional<JsonPath>(JsonPath{}) : std::nullopt});
  return mesh;
}

TriangleMesh read_mesh_file(const std::string& path) { return read_mesh_document(path).mesh; }

}  // namespace texwarp::mesh
