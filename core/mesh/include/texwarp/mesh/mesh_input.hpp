// Mesh input: Wavefront OBJ (parsed by tinyobjloader; triangles only, other elements ignored) and the JSON form
// {"vertices", "triangles"} (decoded by proto/mesh_spec_codec into a MeshDataSpec).
#pragma once

#include <string>
#include <string_view>

#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/input_location.hpp"
#include "texwarp/proto/mesh_data_spec.hpp"

namespace texwarp::mesh {

// Largest mesh file read (bytes): a guard against feeding the parser something that is not a mesh.
inline constexpr long long kMaxMeshFileBytes = 1LL << 30;

// OBJ text → mesh, faces in file order over all groups/objects; errors are at `where` (the file, or none).
// InputError for a parse error or a face that is not a triangle. Not validated.
TriangleMesh parse_obj_mesh(std::string_view text, const proto::InputLocation& where);

// The JSON form's mesh. Not validated.
TriangleMesh mesh_from_spec(const proto::MeshDataSpec& spec);

// Reads a .obj or .json mesh file and validates it (validate_mesh); InputError naming the file.
TriangleMesh read_mesh_file(const std::string& path);

}  // namespace texwarp::mesh
