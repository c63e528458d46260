// MeshDataSpec: a triangle mesh in its JSON form {"vertices": [[x, y, z], ...], "triangles": [[a, b, c], ...]}
// (0-based vertex indices): a job's inline mesh and the .json mesh file. Decoded, not yet validated as a mesh.
#pragma once

#include <array>
#include <vector>

#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

struct MeshDataSpec {
  std::vector<std::array<double, 3>> vertices;  // finite coordinates
  std::vector<std::array<int, 3>> triangles;    // non-negative vertex indices (range checked by mesh validation)
  friend TEXWARP_API bool operator==(const MeshDataSpec&, const MeshDataSpec&);
};

}  // namespace texwarp::proto
