// Mesh input: Wavefront OBJ (parsed by tinyobjloader; triangles, quads and n-gons, the latter triangulated by ear
// clipping; other elements ignored), the JSON form {"vertices", "triangles"} (decoded by proto/mesh_spec_codec into a
// MeshDataSpec) and glTF 2.0 (.gltf, .glb: gltf_mesh.hpp).
#pragma once

#include <string>
#include <string_view>

#include "texwarp/mesh/mesh_file.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/input_location.hpp"
#include "texwarp/proto/mesh_data_spec.hpp"

namespace texwarp::mesh {

// Largest mesh file read (bytes): a guard against feeding the parser something that is not a mesh.
inline constexpr long long kMaxMeshFileBytes = 1LL << 30;

// OBJ text → mesh, input faces in file order over all groups/objects (f lines of 3 or more vertices), each
// triangulated (polygon_triangulation.hpp); errors are at `where` (the file, or none). InputError for a parse error
// or a polygon that cannot be triangulated. Not validated.
MeshFile parse_obj_file(std::string_view text, const proto::InputLocation& where);
TriangleMesh parse_obj_mesh(std::string_view text, const proto::InputLocation& where);  // its triangles

// The JSON form's mesh. Not validated.
TriangleMesh mesh_from_spec(const proto::MeshDataSpec& spec);

// A mesh file's bytes in `format` (not validated); InputError at `where`. `gltf`: the primitive of a glTF file.
MeshFile parse_mesh_bytes(std::string_view bytes, proto::MeshFormat format, const proto::GltfSelectionSpec& gltf,
                          const proto::InputLocation& where);

// Reads a .obj, .json, .gltf or .glb mesh file and validates it (validate_mesh); InputError naming the file.
MeshFile read_mesh_document(const std::string& path, const proto::GltfSelectionSpec& gltf = {});
TriangleMesh read_mesh_file(const std::string& path);  // its triangles

}  // namespace texwarp::mesh
