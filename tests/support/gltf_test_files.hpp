// glTF test files built from a TriangleMesh byte by byte (independently of core/mesh's glTF code): one mesh with one
// triangle primitive, its node, scene and material; as JSON + binary parts that tests edit into hostile files.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh::testing {

struct GltfFileOptions {
  int index_type = 5125;     // indices' componentType: 5121 (byte), 5123 (short), 5125 (int); 0: no indices
  bool split = false;        // one glTF vertex per triangle corner (as exporters split at seams): nothing shared
  bool interleaved = false;  // POSITION and NORMAL interleaved in one buffer view (byteStride 24)
  std::string mesh_name = "grid";
};

// The file's JSON and its one buffer's bytes. Attributes: POSITION, NORMAL (0, 0, 1), TEXCOORD_0 (x / 10, y / 10),
// TEXCOORD_1 (0.25, 0.75); material 0 "paint" with a base colour factor.
// NOLINTNEXTLINE(bugprone-exception-escape): its implicit moves are noexcept; clang-tidy 14 says nlohmann::json's throw
struct GltfParts {
  nlohmann::json json;
  std::string bin;
};
GltfParts gltf_parts(const TriangleMesh& mesh, const GltfFileOptions& options = {});

// .gltf text (the buffer as a data: URI) or .glb bytes (the buffer as the BIN chunk).
std::string gltf_text(GltfParts parts);
std::string glb_bytes(const GltfParts& parts);

}  // namespace texwarp::mesh::testing
