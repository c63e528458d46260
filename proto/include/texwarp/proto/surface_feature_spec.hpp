// SurfaceFeatureSetSpec: a mesh job's surface features as they travel (the map-mesh feature file, the job's
// "mesh.features"): texture sources in pixels pinned to the surface by face + barycentric weights, a 3D point or a
// vertex; gradient features add a tangent direction and a texel density. Values as given (validated).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "texwarp/proto/export.hpp"
#include "texwarp/proto/warp_spec.hpp"

namespace texwarp::proto {

struct FaceTargetSpec {
  int face = -1;                        // 0-based mesh face id
  std::array<double, 3> barycentric{};  // each ≥ −kBarycentricSlack, summing to 1 within kBarycentricSlack
  friend TEXWARP_API bool operator==(const FaceTargetSpec&, const FaceTargetSpec&);
};
struct PointTargetSpec {
  std::array<double, 3> point{};  // world units; snapped to the region within the snap tolerance
  friend TEXWARP_API bool operator==(const PointTargetSpec&, const PointTargetSpec&);
};
struct VertexTargetSpec {
  int vertex = -1;  // 0-based mesh vertex id
  friend TEXWARP_API bool operator==(const VertexTargetSpec&, const VertexTargetSpec&);
};
using SurfaceTargetSpec = std::variant<FaceTargetSpec, PointTargetSpec, VertexTargetSpec>;

// Where the texture's u axis should point on the surface and how dense the texture is there.
struct SurfaceFrameSpec {
  std::array<double, 3> direction{};  // a non-zero tangent direction (its normal component is dropped)
  double texels_per_unit = 1.0;       // > 0: texture pixels per world unit along `direction`
  friend TEXWARP_API bool operator==(const SurfaceFrameSpec&, const SurfaceFrameSpec&);
};

struct SurfaceFeatureSpec {
  std::string id;  // optional in the file; empty when absent
  std::array<double, 2> source{};
  SurfaceTargetSpec target;
  std::optional<FrameSpec> source_frame;  // both present: a gradient feature
  std::optional<SurfaceFrameSpec> target_frame;
  friend TEXWARP_API bool operator==(const SurfaceFeatureSpec&, const SurfaceFeatureSpec&);
};

struct SurfaceFeatureSetSpec {
  double alpha = 2.0;
  Prealign prealign = Prealign::kSimilarity;
  double tolerance_px = 0.01;
  std::optional<double> snap_tolerance;  // world units, ≥ 0; none: a fraction of the region's diagonal
  std::vector<SurfaceFeatureSpec> features;
  friend TEXWARP_API bool operator==(const SurfaceFeatureSetSpec&, const SurfaceFeatureSetSpec&);
};

// Barycentric weights must be ≥ −kBarycentricSlack each and sum to 1 within kBarycentricSlack.
inline constexpr double kBarycentricSlack = 1e-6;

}  // namespace texwarp::proto
