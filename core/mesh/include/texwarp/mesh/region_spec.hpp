// RegionSpec: the region file {"faces": [f, ...]} or {"boundary": [v0, v1, ...], "seed_face": f} (0-based),
// its strict decoder (JSON paths in errors), and the region it selects on a mesh.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

struct RegionSpec {
  std::vector<int> faces;     // a face set, or
  std::vector<int> boundary;  // a closed vertex curve (consecutive vertices joined by shortest edge paths)
  int seed_face = -1;         // with a face on the side to keep

  bool is_curve() const { return !boundary.empty(); }
};

// Exactly one of "faces" or "boundary" (+ "seed_face"); ids are non-negative integers, faces listed once.
RegionSpec decode_region_spec(const nlohmann::json& value, const std::string& path = "$");

// The region on `mesh` (validated): the whole mesh when `spec` is empty. Errors name `where` (a file name)
// and the JSON path ("$.faces[3]") of an id that is out of range.
MeshRegion select_region(const TriangleMesh& mesh, const std::optional<RegionSpec>& spec, const std::string& where);

}  // namespace texwarp::mesh
