// Surface features: texture features (sources in texture pixels) pinned to the mesh surface by face +
// barycentric weights, a 3D point (snapped to the region) or a vertex; gradient features add a tangent
// direction on the surface and a texel density. Decoded from the map-mesh feature file (surface_feature_codec).
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "texwarp/core/feature.hpp"
#include "texwarp/core/warp_options.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"
#include "texwarp/mesh/vec3.hpp"

namespace texwarp::mesh {

struct FaceTarget {
  int face = -1;            // mesh face id
  Barycentric barycentric;  // non-negative, summing to 1
};
struct PointTarget {
  Vec3 point;  // world units; snapped to the nearest point of the region within the snap tolerance
};
struct VertexTarget {
  int vertex = -1;  // mesh vertex id
};
using SurfaceTarget = std::variant<FaceTarget, PointTarget, VertexTarget>;

// Where the texture's u axis should point on the surface and how dense the texture is there.
struct SurfaceFrame {
  Vec3 direction;                // a tangent direction (its component normal to the surface is dropped)
  double texels_per_unit = 1.0;  // texture pixels per world unit along `direction`
};

struct SurfaceFeature {
  std::string id;
  Point source;  // texture pixels (y down)
  SurfaceTarget target;
  std::optional<Frame> source_frame;  // both set: a gradient feature
  std::optional<SurfaceFrame> target_frame;

  bool is_gradient() const { return source_frame.has_value() && target_frame.has_value(); }
};

struct SurfaceFeatureSet {
  WarpOptions options;                   // alpha, prealign, tolerance_px
  std::optional<double> snap_tolerance;  // world units; default: kDefaultSnapFraction × region diagonal
  std::vector<SurfaceFeature> features;
};

// Default snap tolerance for point targets, as a fraction of the region's bounding-box diagonal.
inline constexpr double kDefaultSnapFraction = 0.01;

}  // namespace texwarp::mesh
