// MeshRegion: the part of a mesh to texture, checked to be a single topological disk (one component, no
// pinched vertex, genus 0, exactly one boundary loop), with its faces re-indexed as a mesh of its own.
// Made from the whole mesh, a face set, or a closed vertex curve plus a seed face (flood fill).
#pragma once

#include <span>
#include <string>
#include <vector>

#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp::mesh {

struct MeshRegion {
  std::vector<int> faces;         // mesh face ids, ascending
  std::vector<int> vertices;      // mesh vertex ids, ascending; a vertex's local id is its index here
  std::vector<int> local_vertex;  // per mesh vertex: its local id, −1 outside the region
  std::vector<int> local_face;    // per mesh face: its index in `faces`, −1 outside the region
  TriangleMesh local;             // the region alone: local vertex ids, faces in the order of `faces`
  std::vector<int> boundary;      // the boundary loop, local vertex ids, in the faces' orientation

  int face_count() const { return static_cast<int>(faces.size()); }
  int vertex_count() const { return static_cast<int>(vertices.size()); }
};

// The region made of `faces` (mesh face ids, each in range and listed once: the caller checks) when it is a
// disk; otherwise InputError at `where` saying why, with `subject` ("the region", "the mesh") as its subject:
// no faces, several components, a pinched vertex, closed (no boundary), genus > 0, holes (boundary loops > 1).
MeshRegion disk_region(const TriangleMesh& mesh, std::vector<int> faces, const proto::InputLocation& where,
                       const std::string& subject = "the region");

// The whole (validated) mesh, when it is a disk.
MeshRegion whole_mesh_region(const TriangleMesh& mesh, const proto::InputLocation& where);

// Closes the vertex curve (a last vertex equal to the first is dropped) and joins consecutive vertices that
// share no edge by the shortest edge path between them (Dijkstra on edge lengths). InputError at `where` when
// a vertex id is out of range, fewer than 3 vertices remain, two vertices are not connected, or the closed
// curve passes a vertex twice (it must be simple).
std::vector<int> close_vertex_curve(const TriangleMesh& mesh, std::span<const int> curve,
                                    const proto::InputLocation& where);

// Faces reachable from seed_face through edges that are not on the closed curve (close_vertex_curve first).
// InputError when seed_face is out of range or the curve does not separate the surface (every face reached).
std::vector<int> faces_inside_curve(const TriangleMesh& mesh, std::span<const int> closed_curve, int seed_face,
                                    const proto::InputLocation& where);

}  // namespace texwarp::mesh
