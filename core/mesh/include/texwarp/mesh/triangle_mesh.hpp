// TriangleMesh: an indexed triangle mesh as read from a file (0-based vertex ids, faces in file order).
// Nothing is checked here: validate_mesh (mesh_validation.hpp) says whether the pipeline can use it.
#pragma once

#include <array>
#include <vector>

#include "texwarp/mesh/vec3.hpp"

namespace texwarp::mesh {

using Face = std::array<int, 3>;  // vertex ids, counter-clockwise seen from the front

struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<Face> faces;

  int vertex_count() const { return static_cast<int>(vertices.size()); }
  int face_count() const { return static_cast<int>(faces.size()); }
  Vec3 corner(int face, int k) const { return vertices[faces[face][k]]; }
};

}  // namespace texwarp::mesh
