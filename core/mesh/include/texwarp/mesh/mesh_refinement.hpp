// `refine`: the region's triangles split so that UVs interpolated linearly inside each triangle keep the warp's
// orientation as written (Rivara's longest-edge bisection of every triangle whose UVs are not positive, repeated
// until none is) and every feature inside a face or on an edge becomes a vertex (its UV then exact); new vertices
// and faces map back to the input mesh.
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

using proto::RefinementStop;  // why bisection stopped: proto/mesh_flips_report.hpp

// Called before each pass over the faces that finds a triangle flipped, with the region as it stands (its local faces
// and surface positions), every vertex's texture position (pixels) and the features' vertices: it may move the
// texture positions of the others. Untangling there (texture_mapping.cpp) makes bisection split only the triangles
// untangling alone leaves flipped, and gives it the new vertices to unfold them with.
using RefinementRelax =
    std::function<void(const TriangleMesh& local, std::span<Point> texture_px, std::span<const int> features)>;

struct RefinementOptions {
  int texture_width = 1;  // the original texture: UVs normalise by it (their float32 rounding is checked)
  int texture_height = 1;
  double min_edge_px = 0.16;   // frame edges shorter than this are not bisected (16 × the default 0.01 px tolerance)
  int max_vertex_factor = 16;  // at most this many times the region's vertices (or 64 of them), then stop
  int max_vertices = 0;        // and at most this many in all (what a job's memory budget allows); 0: no such bound
  bool bisect = true;          // false: features made vertices only
  int max_rounds = 0;          // bisection rounds at most (then stop as at the vertex bound); 0: no such bound
  // Before the first pass, every edge joining two features' vertices is split at its midpoint (counted in
  // split_edges), so that no feature's vertex has another as a neighbour: a triangle whose corners are all pins, out
  // of order, cannot be unfolded while its edges stay fixed segments, nor can a pin whose pinned neighbours lie around
  // it in the wrong turn; with free midpoints they can. Within the vertex bound: where it is reached, the splits stop
  // there (stop kVertexLimit).
  bool split_feature_edges = false;
  // When set: run before each pass that finds a flip (`flipped_before` is counted before it); a new vertex then starts
  // at its edge's midpoint UV instead of the warp's inverse (relaxed UVs are no longer the warp's).
  RefinementRelax relax;
};

// What refinement did, without the mesh it made.
struct RefinementCounts {
  int input_vertices = 0;
  int input_faces = 0;
  int feature_vertices = 0;  // features inside a face or on an edge made vertices
  int split_edges = 0;       // edges bisected because a UV triangle was not positive, or between two features
                             // (split_feature_edges)
  int rounds = 0;            // bisection rounds run
  int flipped_before = 0;    // triangles whose UVs were not positive (uv_orientation.hpp) before bisection
  int flipped_after = 0;     // and after it: 0 unless `stop` says why not
  int vertex_limit = 0;      // the bound on the region's vertices
  RefinementStop stop = RefinementStop::kFlipFree;
  bool kept = true;  // false: bisection stopped early with more flips than it started with, so it was dropped

  bool changed_faces() const { return feature_vertices > 0 || split_edges > 0; }
};

struct MeshRefinement : RefinementCounts {
  // The output mesh: the input's vertices, then the new ones; the input's faces by id (a split face keeps one of
  // its parts there), then the new parts.
  TriangleMesh mesh;
  std::vector<int> source_face;                 // per output face: the input face it lies in
  std::vector<SurfacePoint> new_vertices;       // per new vertex (output id = input vertex count + index)
  std::vector<SurfacePoint> feature_locations;  // per feature: on the output mesh, at a corner of a face
};

// Per region vertex (local ids) arrays refine_region keeps in step with the region.
struct RegionVertexData {
  std::vector<Point>& frame_px;    // position in the warped texture (the embedding), pixels
  std::vector<Point>& embedding;   // the planar embedding (world units, y up)
  std::vector<Point>& texture_px;  // UV position in the original texture, pixels
};

// Pixels of the warped texture → pixels of the original texture (the warp's inverse map), in place.
using InverseMap = std::function<void(std::span<Point>)>;

// Refines `region` of `mesh` (replaced by the refined region of MeshRefinement::mesh) and extends `data`:
// new vertices get frame and embedding positions by linear interpolation on their input face and texture
// positions by `inverse_map` (a feature's vertex: its source, f⁻¹(target) exactly; with `relax`, their edge's midpoint
// UV). Terminates: the warp's inverse is a C¹ map with a positive Jacobian, so bisected triangles (whose shapes
// Rivara's bisection keeps bounded) become positive once small enough; the vertex bound, the smallest edge and the
// round bound stop it otherwise (`stop` says which), and are what stops it with `relax`.
MeshRefinement refine_region(const TriangleMesh& mesh, MeshRegion& region, const RegionVertexData& data,
                             std::span<const PlacedFeature> features, const InverseMap& inverse_map,
                             const RefinementOptions& options);

// The mesh the region's ids refer to: the refinement's when there is one, else `input`.
inline const TriangleMesh& output_mesh(const TriangleMesh& input, const std::optional<MeshRefinement>& refinement) {
  return refinement ? refinement->mesh : input;
}

}  // namespace texwarp::mesh
