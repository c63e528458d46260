// Validation of a mesh from outside before any geometry is computed on it: each defect is an InputError
// naming the face or vertex (0-based) and what is wrong with it.
#pragma once

#include <optional>

#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp::mesh {

// Where messages point: `where` (a file, or none) is the error's place; items are named "face 12" /
// "vertex 7", or for a JSON mesh by their JSON path under `json_path` ("$.triangles[12]", "$.vertices[7]").
struct MeshSource {
  proto::InputLocation where;
  std::optional<proto::JsonPath> json_path;  // none: not a JSON mesh
};

// A face is geometrically degenerate when twice its area is below this fraction of its longest edge squared
// (its smallest angle is then about 1e-12 rad): LSCM and every per-triangle measure divide by that area.
inline constexpr double kDegenerateAreaFraction = 1e-12;

// Checks, in this order, throwing at the first defect: no faces; non-finite coordinates; vertex ids out of
// range; a face using a vertex twice; a zero-area face; two faces on the same three vertices; an edge shared
// by more than two faces (non-manifold); two faces using an edge in the same direction (inconsistent
// orientation); vertices no face uses.
void validate_mesh(const TriangleMesh& mesh, const MeshSource& source);

}  // namespace texwarp::mesh
