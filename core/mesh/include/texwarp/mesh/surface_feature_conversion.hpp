// Conversion of the wire's surface features (proto::SurfaceFeatureSetSpec, decoded by proto/mesh_spec_codec) to the
// mesh pipeline's: frames in radians, barycentric weights clamped to ≥ 0 and renormalised to sum 1.
#pragma once

#include "texwarp/mesh/surface_feature.hpp"
#include "texwarp/proto/surface_feature_spec.hpp"

namespace texwarp::mesh {

SurfaceFeatureSet surface_features_from_spec(const proto::SurfaceFeatureSetSpec& spec);

}  // namespace texwarp::mesh
