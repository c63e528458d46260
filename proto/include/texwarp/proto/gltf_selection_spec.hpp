// GltfSelectionSpec: which primitive of a glTF file a mesh job textures ("mesh.source.gltf": {"mesh": name or index,
// "primitive": index}); none given: the first primitive of the first mesh.
#pragma once

#include <optional>
#include <string>

#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

struct GltfSelectionSpec {
  std::optional<std::string> mesh_name;  // at most one of mesh_name, mesh_index; neither: mesh 0
  std::optional<int> mesh_index;
  int primitive = 0;  // in the mesh's "primitives"
  friend TEXWARP_API bool operator==(const GltfSelectionSpec&, const GltfSelectionSpec&);
};

}  // namespace texwarp::proto
