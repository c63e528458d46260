// Flipped triangles of a planar embedding (against the majority orientation) and their repair: Floater's
// mean-value embedding with the boundary on a convex polygon (a circle), bijective for a disk (Floater 2003).
#pragma once

#include <span>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/mesh_flips_report.hpp"

namespace texwarp::mesh {

// Faces (ids of `mesh`) whose signed area in `positions` (x + i·y, y up) is zero or of the sign opposite to
// the majority of faces.
std::vector<int> embedding_flipped_faces(const TriangleMesh& mesh, std::span<const Point> positions);

// Mean-value embedding of a disk (Floater, "Mean value coordinates", CAGD 2003): the boundary loop (in the
// faces' orientation) on a circle, spaced by 3D edge length, counter-clockwise; every interior vertex the
// mean-value convex combination of its neighbours (sparse LU). Scaled so its area equals the surface area.
// NumericalError if the solve fails.
std::vector<Point> mean_value_embedding(const TriangleMesh& mesh, std::span<const int> boundary);

struct EmbeddingRepair {
  std::vector<Point> positions;
  proto::EmbeddingMethod method = proto::EmbeddingMethod::kLscm;
  std::vector<int> flipped_faces;  // of the given embedding (local face ids); empty: kept as it was
};

// The given embedding when no face flips; otherwise the mean-value embedding (method kMeanValue).
EmbeddingRepair repair_embedding(const TriangleMesh& mesh, std::span<const int> boundary, std::vector<Point> positions);

}  // namespace texwarp::mesh
