// Wire surface features → the mesh pipeline's: see surface_feature_conversion.hpp.
#include "texwarp/mesh/surface_feature_conversion.hpp"

#include <algorithm>
#include <variant>

#include "texwarp/core/feature_conversion.hpp"

namespace texwarp::mesh {
namespace {

Vec3 vec3(const std::array<double, 3>& v) { return {v[0], v[1], v[2]}; }

SurfaceTarget target_from_spec(const proto::SurfaceTargetSpec& spec) {
  if (const auto* f = std::get_if<proto::FaceTargetSpec>(&spec)) {
    // Weights within the slack of the simplex (checked on decoding) are put back on it exactly.
    Barycentric c{std::max(f->barycentric[0], 0.0), std::max(f->barycentric[1], 0.0), std::max(f->barycentric[2], 0.0)};
    const double s = c[0] + c[1] + c[2];
    for (double& x : c) x /= s;
    return FaceTarget{f->face, c};
  }
  if (const auto* p = std::get_if<proto::PointTargetSpec>(&spec)) return PointTarget{vec3(p->point)};
  return VertexTarget{std::get<proto::VertexTargetSpec>(spec).vertex};
}

}  // namespace

SurfaceFeatureSet surface_features_from_spec(const proto::SurfaceFeatureSetSpec& spec) {
  SurfaceFeatureSet set;
  set.options.alpha = spec.alpha;
  set.options.prealign = spec.prealign;
  set.options.tolerance_px = spec.tolerance_px;
  set.snap_tolerance = spec.snap_tolerance;
  set.features.reserve(spec.features.size());
  for (const proto::SurfaceFeatureSpec& f : spec.features) {
    SurfaceFeature out;
    out.id = f.id;
    out.source = Point(f.source[0], f.source[1]);
    out.target = target_from_spec(f.target);
    if (f.source_frame) out.source_frame = frame_from_spec(*f.source_frame);
    if (f.target_frame)
      out.target_frame = SurfaceFrame{vec3(f.target_frame->direction), f.target_frame->texels_per_unit};
    set.features.push_back(std::move(out));
  }
  return set;
}

}  // namespace texwarp::mesh
