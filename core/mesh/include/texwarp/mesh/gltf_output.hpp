// The textured glTF: the input document written back (.gltf with the new data embedded as a data: URI buffer, or
// .glb with it appended to the BIN chunk) with the primitive's TEXCOORD_0 pointing at a new accessor of new UVs.
// Everything else in the document (nodes, other attributes and TEXCOORD_n, materials, extensions) is kept as read.
// Refined (faces split, new vertices): the primitive gets new accessors for every attribute and its indices; a new
// vertex gets one glTF vertex per set of attribute values around it (two across a seam, as exporters split them),
// its attributes interpolated on the input triangle it lies in (NORMAL and TANGENT's direction renormalised), or its
// nearest corner's where GltfAttribute::interpolated says (a skin's joints and weights), morph targets likewise.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>

#include "texwarp/mesh/gltf_mesh.hpp"
#include "texwarp/mesh/mesh_refinement.hpp"
#include "texwarp/mesh/mesh_region.hpp"

namespace texwarp::mesh {

// uvs: per region vertex (local id), with glTF's top-left origin (v = y / height). A glTF vertex used by a region
// triangle gets its vertex's UV; every other glTF vertex keeps its TEXCOORD_0 as read ({0, 0} where it had none).
// base_color_uri: when set (the warped texture's file name), the primitive gets a copy of its material (or a new
// one) whose pbrMetallicRoughness.baseColorTexture is that image, so other primitives sharing the material keep it.
// refinement: the region's refinement when it changed the faces (`region` then refers to refinement->mesh); it needs
// gltf.unrefinable empty (std::invalid_argument otherwise: the caller refuses refinement first).
// Returns the file's bytes (.glb when gltf.binary).
std::string textured_gltf_bytes(const GltfMesh& gltf, const MeshRegion& region,
                                std::span<const std::array<double, 2>> uvs,
                                const std::optional<std::string>& base_color_uri,
                                const MeshRefinement* refinement = nullptr);

}  // namespace texwarp::mesh
