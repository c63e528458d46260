// The textured glTF: the input document written back (.gltf with the new data embedded as a data: URI buffer, or
// .glb with it appended to the BIN chunk) with the primitive's TEXCOORD_0 pointing at a new accessor of new UVs.
// Everything else in the document (nodes, other attributes and TEXCOORD_n, materials, extensions) is kept as read.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>

#include "texwarp/mesh/gltf_mesh.hpp"
#include "texwarp/mesh/mesh_region.hpp"

namespace texwarp::mesh {

// uvs: per region vertex (local id), with glTF's top-left origin (v = y / height). A glTF vertex used by a region
// triangle gets its vertex's UV; every other glTF vertex keeps its TEXCOORD_0 as read ({0, 0} where it had none).
// base_color_uri: when set (the warped texture's file name), the primitive gets a copy of its material (or a new
// one) whose pbrMetallicRoughness.baseColorTexture is that image, so other primitives sharing the material keep it.
// Returns the file's bytes (.glb when gltf.binary).
std::string textured_gltf_bytes(const GltfMesh& gltf, const MeshRegion& region,
                                std::span<const std::array<double, 2>> uvs,
                                const std::optional<std::string>& base_color_uri);

}  // namespace texwarp::mesh
