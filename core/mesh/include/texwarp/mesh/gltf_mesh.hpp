// glTF 2.0 input (.gltf with embedded buffers, .glb): one triangle primitive read through tinygltf, its vertices
// welded by position, kept with the document so that gltf_output.hpp can write the file back with new UVs.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/gltf_selection_spec.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp::mesh {

// NOLINTNEXTLINE(bugprone-exception-escape): its implicit moves are noexcept; clang-tidy 14 says nlohmann::json's throw
struct GltfMesh {
  nlohmann::json document;   // the file's JSON (the .glb's JSON chunk), kept for output
  std::string binary_chunk;  // .glb: the BIN chunk's payload (buffer 0), else empty
  bool binary = false;       // read from a .glb
  int mesh_index = 0;        // the primitive read: meshes[mesh_index].primitives[primitive_index]
  int primitive_index = 0;
  // Per glTF vertex (element of the POSITION accessor): its mesh vertex, −1 when no triangle uses it. Vertices
  // with bit-equal positions are welded (exporters split vertices at UV and normal seams); mesh vertex ids are
  // numbered in the order of their first glTF vertex.
  std::vector<int> mesh_vertex;
  std::vector<std::uint32_t> corners;  // per triangle corner (3 per mesh face): its glTF vertex
  // Per glTF vertex: its TEXCOORD_0 as read (glTF's top-left origin), {0, 0} when the primitive has none.
  std::vector<std::array<double, 2>> texcoord0;
  TriangleMesh mesh;  // one face per glTF triangle, in index order (face ids are the primitive's triangle ids)
};

// Largest glTF accessor element count read (POSITION, indices): bounds the work on a hostile file.
inline constexpr long long kMaxGltfElements = 1LL << 28;

// bytes → the selected primitive (none selected: primitive 0 of mesh 0). InputError at `where` (the file, or a
// JSON path) naming what is wrong: not glTF 2.0, a buffer that is not embedded (external file URIs are not read),
// an accessor or buffer view out of range, wrong counts, strides or types, sparse accessors, a primitive that is
// not made of triangles (mode 4), no POSITION, index out of range, non-finite positions, an unknown mesh/primitive.
// Not validated as a mesh (validate_mesh).
GltfMesh parse_gltf_mesh(std::string_view bytes, bool binary, const proto::GltfSelectionSpec& selection,
                         const proto::InputLocation& where);

}  // namespace texwarp::mesh
