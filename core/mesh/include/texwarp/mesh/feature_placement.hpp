// Surface features placed in the embedding: each target resolved to a face of the region + barycentric
// weights and carried to the texture frame (pixels) through the embedding, giving the warp's features; a
// gradient target's 3D direction and texel density become a 2D frame through the embedding's Jacobian.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "texwarp/core/feature.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/surface_feature.hpp"
#include "texwarp/mesh/surface_location.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::mesh {

struct PlacedFeature {
  SurfacePoint location;       // region face (mesh id) + barycentric weights
  Vec3 position;               // world units
  double snap_distance = 0.0;  // point targets: distance from the given point to `position`
  Feature feature;             // source (texture px), target (frame px), frames: one feature of the warp
};

// J·d: the tangent vector d (world units, its normal component dropped) carried by the affine map of the
// triangle p0 p1 p2 onto q0 q1 q2 (frame pixels). Returns 0 when d is normal to the triangle.
Point map_tangent(Vec3 p0, Vec3 p1, Vec3 p2, Point q0, Point q1, Point q2, Vec3 d);

// Target frame of a gradient feature on face `face` (mesh id): angle of J·d̂ in the frame (radians from +x
// towards +y) and scale s0·|J·d̂|/texels_per_unit, so that the warp's Jacobian there, S·e^{iφ} with
// S = s1/s0 and φ = θ1 − θ0 (Eq. 4), carries the texture's axis at angle θ0 onto d with texels_per_unit
// texels per world unit. InputError at `where` when d is (nearly) normal to the face.
Frame gradient_target_frame(const TriangleMesh& mesh, const MeshRegion& region, std::span<const Point> frame_px,
                            int face, const SurfaceFrame& target, const Frame& source, const proto::JsonPath& where);

// Resolves every feature (InputError at "<path>.features[i].target..." for an id out of range or outside the
// region, or a point farther from the region than the snap tolerance) and builds the warp features.
// frame_px: per region vertex (local id), its position in the texture frame.
std::vector<PlacedFeature> place_surface_features(const TriangleMesh& mesh, const MeshRegion& region,
                                                  std::span<const Point> frame_px, const SurfaceFeatureSet& set,
                                                  const proto::JsonPath& path = {});

}  // namespace texwarp::mesh
