// The texture-mapping pipeline of the paper's Section 3: region → free-boundary LSCM → placed in the warped
// texture's frame → surface features in frame pixels → WarpProblem → each embedded vertex pulled back
// through the inverse map f⁻¹ into the ORIGINAL texture → flips untangled on the input's faces, else refined and
// untangled (or refined and untangled by turns) until no UV triangle flips → UV stretch lowered without a flip, pins
// fixed; then its quality (stretch, shear, flips, residuals).
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "texwarp/core/run_control.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/mesh/feature_placement.hpp"
#include "texwarp/mesh/frame_placement.hpp"
#include "texwarp/mesh/lscm.hpp"
#include "texwarp/mesh/mesh_refinement.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/surface_feature.hpp"
#include "texwarp/mesh/uv_metrics.hpp"
#include "texwarp/mesh/uv_optimization.hpp"
#include "texwarp/mesh/uv_untangling.hpp"
#include "texwarp/proto/uv_optimize.hpp"

namespace texwarp::mesh {

struct TextureMappingOptions {
  int texture_width = 0;  // the original texture, pixels: feature sources live there, UVs normalise by it
  int texture_height = 0;
  int frame_width = 0;  // the warped texture (the embedding's frame); 0: the original's size
  int frame_height = 0;
  double margin_px = 8.0;        // free band around the embedding in the frame
  bool rotate_to_fit = true;     // see FramePlacementOptions
  bool refine = false;           // split triangles the warp flips and faces at features (mesh_refinement.hpp)
  int max_refined_vertices = 0;  // refinement's bound on the region's vertices from a memory budget; 0: none
  proto::UvOptimize optimize = proto::UvOptimize::kNone;  // kStretch: lower the UVs' stretch once flip-free
};

// What `optimize` did (uv_optimization.hpp): skipped while the warp's UVs still flip somewhere.
struct UvOptimizationStage {
  bool applied = false;
  std::string skipped;     // why not applied
  UvOptimization result;   // when applied
  UvMetrics before;        // the UVs into the original texture before it
  std::vector<int> fixed;  // local vertex ids held: the pins (and one-rings), the corners of faces still flipped
  double seconds = 0.0;
};

// What `optimize: stretch` did first when the warp's UVs flipped: untangling (uv_untangling.hpp), the features'
// vertices held.
struct UvUntanglingStage {
  UvUntangling result;
  double seconds = 0.0;
};

struct TextureMapping {
  MeshRegion region;
  LscmEmbedding lscm;    // per region vertex (local ids), world units, y up; the repaired embedding if LSCM flipped
  FramePlacement frame;  // per region vertex: position in the warped texture, pixels
  int frame_width = 0;
  int frame_height = 0;
  std::vector<PlacedFeature> features;  // in file order
  std::optional<WarpProblem> problem;   // the warp f: original texture → frame
  std::vector<Point> texture_px;        // per region vertex: f⁻¹(frame position), original texture pixels
  double lscm_seconds = 0.0;
  double warp_seconds = 0.0;  // inverse map of the input's vertices (and choosing between two plans: see map_texture)
  proto::EmbeddingMethod embedding = proto::EmbeddingMethod::kLscm;
  std::vector<int> lscm_flipped_faces;  // mesh face ids the LSCM embedding flipped (then replaced)
  // With `refine` when it changed the faces (`region` then refers to refinement->mesh); refinement_counts whenever
  // it ran.
  std::optional<MeshRefinement> refinement;
  std::optional<RefinementCounts> refinement_counts;
  double refinement_seconds = 0.0;
  std::optional<UvUntanglingStage> untangling;      // with `optimize: stretch`, when the UVs flipped
  std::optional<UvOptimizationStage> optimization;  // with `optimize: stretch`
};

// The bound on the region's vertices of bisection alternating with untangling (texture_mapping.cpp): the input
// region's vertices plus (kAlternatingFaceFactor − 1)/2 × its faces; under a memory budget on the region's vertices
// (`max_vertices` > 0), also no more new vertices than the budget leaves beside the refinement already made, which is
// held meanwhile as the state to go back to (`kept_vertices`, the region's vertices in it). Below `input_vertices`: no
// room to try.
int alternating_vertex_limit(int input_vertices, int input_faces, int kept_vertices, int max_vertices);

// Runs the pipeline; an LSCM embedding that flips a triangle is replaced by the mean-value embedding. InputError for
// bad options, features (JSON paths under `features_path`) or a problem the warp refuses (collisions, duplicates);
// NumericalError if LSCM or the integration fails.
TextureMapping map_texture(WarpBackend& backend, const TriangleMesh& mesh, MeshRegion region,
                           const SurfaceFeatureSet& features, const TextureMappingOptions& options,
                           const RunControl& control = {}, const proto::JsonPath& features_path = {});

struct FlippedFace {
  int face = 0;  // output face id (mesh id, or refinement->mesh's)
  proto::FlipCause cause = proto::FlipCause::kWarp;
};

struct MappingQuality {
  UvMetrics texture;                // the UVs into the original texture (measured in its square pixels)
  UvMetrics frame;                  // the UVs into the warped texture (the LSCM embedding)
  std::vector<double> residual_px;  // per feature: |UVs interpolated at its surface point − its source|
  double max_residual_px = 0.0;
  double mean_residual_px = 0.0;
  int vertices_outside_texture = 0;  // texture positions outside [0, width] × [0, height]
  std::vector<FlippedFace> flips;    // the texture UVs' flipped triangles (texture.flipped of them), by cause
};

// Quality of per-vertex texture positions `texture_px` (the mapping's own, or a baseline's) for `mapping`.
// `mesh` is the input mesh (the refined one is taken from the mapping).
MappingQuality evaluate_mapping(const TriangleMesh& mesh, const TextureMapping& mapping,
                                std::span<const Point> texture_px, const TextureMappingOptions& options,
                                bool per_triangle = false);

// Pixel positions (y down) as texture-domain positions with v up, the orientation uv_metrics expects.
std::vector<Point> pixels_to_domain(std::span<const Point> pixels);

}  // namespace texwarp::mesh
