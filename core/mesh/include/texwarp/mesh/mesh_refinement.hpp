// `refine`: the region's triangles split so that UVs interpolated linearly inside each triangle keep the warp's
// orientation (longest-edge bisection of every triangle the warp flips, repeated) and every feature inside a face
// or on an edge becomes a vertex (its UV then exact); new vertices and faces map back to the input mesh.
#pragma once

#include <functional>
#include <span>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/mesh/feature_placement.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/surface_location.hpp"
#include "texwarp/proto/mesh_flips_report.hpp"

namespace texwarp::mesh {

struct MeshRefinement {
  // The output mesh: the input's vertices, then the new ones; the input's faces by id (a split face keeps one of
  // its parts there), then the new parts.
  TriangleMesh mesh;
  std::vector<int> source_face;                 // per output face: the input face it lies in
  std::vector<SurfacePoint> new_vertices;       // per new vertex (output id = input vertex count + index)
  std::vector<SurfacePoint> feature_locations;  // per feature: on the output mesh, at a corner of a face
  int input_vertices = 0;
  int input_faces = 0;
  int feature_vertices = 0;  // features inside a face or on an edge made vertices
  int split_edges = 0;       // edges bisected because the warp flipped a triangle
  int rounds = 0;            // bisection rounds run
};

// Per region vertex (local ids) arrays refine_region keeps in step with the region.
struct RegionVertexData {
  std::vector<Point>& frame_px;    // position in the warped texture (the embedding), pixels
  std::vector<Point>& embedding;   // the planar embedding (world units, y up)
  std::vector<Point>& texture_px;  // UV position in the original texture, pixels
};

// Pixels of the warped texture → pixels of the original texture (the warp's inverse map), in place.
using InverseMap = std::function<void(std::span<Point>)>;

inline constexpr int kMaxRefinementRounds = 24;

// Refines `region` of `mesh` (replaced by the refined region of MeshRefinement::mesh) and extends `data`:
// new vertices get frame and embedding positions by linear interpolation on their input face and texture
// positions by `inverse_map` (a feature's vertex: its source, f⁻¹(target) exactly). Stops after `max_rounds`
// bisection rounds or when the vertex count would pass 8× the region's (flips may then remain).
MeshRefinement refine_region(const TriangleMesh& mesh, MeshRegion& region, const RegionVertexData& data,
                             std::span<const PlacedFeature> features, const InverseMap& inverse_map,
                             int max_rounds = kMaxRefinementRounds);

// The mesh the region's ids refer to: the refinement's when there is one, else `input`.
inline const TriangleMesh& output_mesh(const TriangleMesh& input, const std::optional<MeshRefinement>& refinement) {
  return refinement ? refinement->mesh : input;
}

// Whether the texture-pixel triangle a b c (y down) is flipped against the front (counter-clockwise, v up).
bool texture_triangle_flipped(Point a, Point b, Point c);

}  // namespace texwarp::mesh
