// Strict decoder of the map-mesh feature file {"alpha", "prealign", "tolerance_px", "snap_tolerance",
// "features": [{"id", "source", "target": {"face", "barycentric"} | {"point"} | {"vertex"}, "source_frame",
// "target_frame": {"direction", "texels_per_unit"}}]}: unknown keys and bad values are InputErrors at their path.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/mesh/surface_feature.hpp"

namespace texwarp::mesh {

// Barycentric weights must be ≥ −kBarycentricSlack each and sum to 1 within kBarycentricSlack; they are then
// clamped and renormalised.
inline constexpr double kBarycentricSlack = 1e-6;

SurfaceFeatureSet decode_surface_features(const nlohmann::json& value, const std::string& path = "$");

}  // namespace texwarp::mesh
