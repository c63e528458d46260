// Strict decoder of the map-mesh feature file: {"alpha", "prealign", "tolerance_px", "snap_tolerance",
// "features": [{"id", "source": [x, y], "target": {"face", "barycentric"} | {"point"} | {"vertex"},
// "source_frame": {"angle_deg", "scale"}, "target_frame": {"direction": [x, y, z], "texels_per_unit"}}]}.
// Unknown keys, wrong types and out-of-range values are InputErrors naming the JSON path.
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
