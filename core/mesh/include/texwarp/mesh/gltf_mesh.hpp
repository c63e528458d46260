// glTF 2.0 input (.gltf with embedded buffers, .glb): one triangle primitive read through tinygltf, its vertices
// welded by position, kept with the document and the primitive's vertex attributes so that gltf_output.hpp can write
// the file back with new UVs, and with new vertices where refinement split faces.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/gltf_selection_spec.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp::mesh {

// glTF's componentType FLOAT (tinygltf's TINYGLTF_COMPONENT_TYPE_FLOAT, checked where both are seen).
inline constexpr int kGltfFloat = 5126;

// Bytes of one component of a glTF componentType (BYTE … FLOAT); 0 for a type glTF does not define.
int gltf_component_bytes(int component_type);

// One vertex attribute of the primitive (or of one of its morph targets): what a new vertex inside a triangle gets a
// value of. Its elements are decoded only when a refinement is written (decode_gltf_attributes).
struct GltfAttribute {
  std::string name;         // "POSITION", "NORMAL", "TEXCOORD_1", "JOINTS_0", "_CUSTOM", …
  int target = -1;          // its morph target's index, −1 for the primitive's own attributes
  int accessor = -1;        // its accessor in the document (attributes may share one)
  int component_type = 0;   // glTF componentType as read
  bool normalized = false;  // normalized integers are decoded to [0, 1] (unsigned) or [−1, 1] (signed)
  int components = 0;       // 1 (SCALAR) to 4 (VEC4)
  // Interpolated at a new vertex (written as float) but for a skin's JOINTS_n and WEIGHTS_n, feature ids
  // (_FEATURE_ID_n) and integer custom attributes, which take the nearest corner's values as they are.
  bool interpolated() const {
    const bool integer = component_type != kGltfFloat && !normalized;
    return !(name.rfind("JOINTS_", 0) == 0 || name.rfind("WEIGHTS_", 0) == 0 || name.rfind("_FEATURE_ID_", 0) == 0 ||
             (integer && name.rfind('_', 0) == 0));
  }
};

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
  // Every vertex attribute of the primitive and its morph targets but TEXCOORD_0 (texcoord0), POSITION included.
  std::vector<GltfAttribute> attributes;
  // Why new vertices cannot be written into this primitive (a compressed or sparse attribute, …); empty when they can.
  std::string unrefinable;
  // About what this holds beyond `mesh` for the output (the document as a JSON tree, counted as 3× its text, the BIN
  // chunk and the per-vertex arrays): a job's memory model counts it for as long as the job runs.
  std::uint64_t held_bytes = 0;
  // What writing a refinement adds: its distinct attribute accessors decoded as floats, and as much again written.
  std::uint64_t refinement_bytes = 0;

  // What a job keeps of this for its output as long as it runs: held_bytes, and refinement_bytes when it refines.
  std::uint64_t kept_bytes(bool refine) const { return held_bytes + (refine ? refinement_bytes : 0); }
};

// The attributes' elements as floats (normalized integers by glTF's rules), per distinct accessor: the document is
// read again (tinygltf). For textured_gltf_bytes with a refinement; gltf.unrefinable must be empty.
std::map<int, std::vector<float>> decode_gltf_attributes(const GltfMesh& gltf);

// A .glb container around `json` and `bin` (each padded to 4 bytes); std::length_error past glTF's 4 GiB.
std::string glb_container(const nlohmann::json& json, std::string bin);

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
