// JSON codecs for a mesh job's parts, each also a file of its own for `texwarp map-mesh`: the surface feature file
// (SurfaceFeatureSetSpec), the region file (RegionSpec) and the JSON mesh (MeshDataSpec). Decoding is strict:
// unknown keys, wrong types and out-of-range values are InputErrors naming the JSON path of the offender.
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/proto/json_path.hpp"
#include "texwarp/proto/mesh_data_spec.hpp"
#include "texwarp/proto/region_spec.hpp"
#include "texwarp/proto/surface_feature_spec.hpp"

namespace texwarp::proto {

// {"alpha", "prealign", "tolerance_px", "snap_tolerance", "features": [{"id", "source", "target": {"face",
// "barycentric"} | {"point"} | {"vertex"}, "source_frame", "target_frame": {"direction", "texels_per_unit"}}]}.
SurfaceFeatureSetSpec decode_surface_feature_set(const nlohmann::json& value, const JsonPath& path = {});
nlohmann::json encode_surface_feature_set(const SurfaceFeatureSetSpec& spec);

// Exactly one of "faces" or "boundary" (+ "seed_face"); ids are non-negative integers, faces listed once.
RegionSpec decode_region_spec(const nlohmann::json& value, const JsonPath& path = {});
nlohmann::json encode_region_spec(const RegionSpec& spec);

// {"vertices": [[x, y, z], ...], "triangles": [[a, b, c], ...]}: finite coordinates, non-negative indices.
MeshDataSpec decode_mesh_data(const nlohmann::json& value, const JsonPath& path = {});
nlohmann::json encode_mesh_data(const MeshDataSpec& mesh);

}  // namespace texwarp::proto
