// The mesh report's flip sections: which embedding the UVs were built on (LSCM, or the bijective mean-value
// embedding that replaced a flipped LSCM), each flipped output face and its cause, and what `refine` added.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "texwarp/proto/enum_names.hpp"
#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

// The planar embedding of the region: free-boundary LSCM, or (when LSCM flipped a triangle) Floater's
// mean-value embedding with the boundary on a circle, bijective for a disk.
enum class EmbeddingMethod { kLscm, kMeanValue };

template <>
struct EnumNames<EmbeddingMethod> {
  static constexpr std::array<std::pair<EmbeddingMethod, const char*>, 2> kTable = {
      {{EmbeddingMethod::kLscm, "lscm"}, {EmbeddingMethod::kMeanValue, "mean_value"}}};
};

// Why an output UV triangle is flipped: the embedding flipped it (its warped-texture UVs are flipped too), or
// the warp bends inside it (its corners' UVs reverse orientation although the warp is fold-free).
enum class FlipCause { kEmbedding, kWarp };

template <>
struct EnumNames<FlipCause> {
  static constexpr std::array<std::pair<FlipCause, const char*>, 2> kTable = {
      {{FlipCause::kEmbedding, "embedding"}, {FlipCause::kWarp, "warp"}}};
};

// Why refinement stopped: no UV triangle flips; the vertex bound was reached; the triangles still flipped are at
// the smallest size the vertices' integration tolerance leaves meaningful; no bisection was needed because
// untangling on the input's faces (features made vertices) left no flip; or bisection alternating with untangling
// ran its rounds.
enum class RefinementStop { kFlipFree, kVertexLimit, kMinEdge, kUntangled, kRoundLimit };

template <>
struct EnumNames<RefinementStop> {
  static constexpr std::array<std::pair<RefinementStop, const char*>, 5> kTable = {
      {{RefinementStop::kFlipFree, "flip_free"},
       {RefinementStop::kVertexLimit, "vertex_limit"},
       {RefinementStop::kMinEdge, "min_edge"},
       {RefinementStop::kUntangled, "untangled"},
       {RefinementStop::kRoundLimit, "round_limit"}}};
};

struct EmbeddingReport {
  EmbeddingMethod method = EmbeddingMethod::kLscm;
  std::vector<int> lscm_flipped_faces;  // mesh face ids LSCM flipped (then repaired by the mean-value embedding)
  TEXWARP_API bool operator==(const EmbeddingReport&) const;
};

struct FlippedFaceReport {
  int face = 0;                    // output face id (mesh.obj)
  std::optional<int> source_face;  // the input face it lies in, when `refine` changed the faces
  FlipCause cause = FlipCause::kWarp;
  TEXWARP_API bool operator==(const FlippedFaceReport&) const;
};

// What `refine` did: vertices added at features inside faces and at midpoints of edges of triangles the warp
// flipped (Rivara's longest-edge bisection, until every UV triangle is positive as written); output faces and
// vertices beyond the input's ids are new (see `source_face`, `source`).
struct RefinementReport {
  int feature_vertices = 0;  // features inside a face or on an edge that became vertices
  int split_edges = 0;       // edges split at their midpoint: the warp flipped a triangle, or two pins shared it
  int rounds = 0;            // split rounds until no triangle flipped (or the limit)
  int added_vertices = 0;
  int added_faces = 0;
  int output_vertices = 0;  // in mesh.obj
  int output_faces = 0;
  std::optional<int> flipped_before;   // UV triangles not positive before bisection (added)
  std::optional<int> flipped_after;    // after it: 0 unless `stop` says why not (added)
  std::optional<int> vertex_limit;     // the bound on the region's vertices (added)
  std::optional<RefinementStop> stop;  // (added)
  std::optional<bool> kept;            // false: stopped early with more flips than before, so dropped (added)
  std::optional<double> seconds;       // (added)
  TEXWARP_API bool operator==(const RefinementReport&) const;
};

// Where a vertex `refine` added lies on the input mesh: an input face and barycentric weights in it, over `corners`
// (the input vertices of the face's triangle that holds it, in the weights' order).
struct SourcePointReport {
  int face = 0;
  std::array<double, 3> barycentric{};
  std::optional<std::array<int, 3>> corners;  // added after the first version
  TEXWARP_API bool operator==(const SourcePointReport&) const;
};

}  // namespace texwarp::proto
