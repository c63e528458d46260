// Topology of a validated (edge-manifold, consistently oriented) triangle mesh: face neighbours across edges,
// connected components, boundary loops and vertices where the surface pinches (several fans of faces).
#pragma once

#include <array>
#include <vector>

#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

struct MeshTopology {
  // neighbour[f][k]: the face across edge k of face f (from corner k to corner k+1), −1 on the boundary.
  std::vector<std::array<int, 3>> neighbour;
  int edge_count = 0;
  std::vector<int> component;  // per face, 0..component_count−1, numbered in order of their lowest face
  int component_count = 0;
  // Boundary loops as vertex ids in the order of the faces' orientation, each starting at its lowest vertex;
  // loops ordered by that vertex. Meaningful only when there is no pinched vertex.
  std::vector<std::vector<int>> boundary_loops;
  // Vertices whose faces form more than one fan (the surface touches itself there), ascending.
  std::vector<int> pinched_vertices;

  int euler_characteristic(int vertex_count) const {
    return vertex_count - edge_count + static_cast<int>(neighbour.size());
  }
};

MeshTopology analyse_topology(const TriangleMesh& mesh);

}  // namespace texwarp::mesh
