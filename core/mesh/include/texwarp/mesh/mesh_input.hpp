// Mesh input: Wavefront OBJ (parsed by tinyobjloader; triangles only, other elements ignored) and the inline
// JSON form {"vertices": [[x, y, z], ...], "triangles": [[a, b, c], ...]} (0-based, strict keys).
#pragma once

#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

// Largest mesh file read (bytes): a guard against feeding the parser something that is not a mesh.
inline constexpr long long kMaxMeshFileBytes = 1LL << 30;

// OBJ text → mesh, faces in file order over all groups/objects; `name` names the source in errors.
// InputError for a parse error or a face that is not a triangle. Not validated.
TriangleMesh parse_obj_mesh(std::string_view text, const std::string& name);

// Inline JSON mesh at `path`; InputError naming the JSON path of any offender. Not validated.
TriangleMesh decode_mesh_json(const nlohmann::json& value, const std::string& path = "$");

// Reads a .obj or .json mesh file and validates it (validate_mesh); InputError naming the file.
TriangleMesh read_mesh_file(const std::string& path);

}  // namespace texwarp::mesh
