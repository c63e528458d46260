// Distortion of a texture mapping, as in Seo & Cordier's Table 1: L² stretch (Sander, Snyder, Gortler,
// Hoppe, "Texture mapping progressive meshes", SIGGRAPH 2001) and L² shear (Sheffer, Lévy, Mogilnitsky,
// Bogomyakov, "ABF++", ACM TOG 24(2) 2005), plus flipped and degenerate triangles in UV space.
#pragma once

#include <span>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

// Per triangle, from the affine map S: texture domain → surface, with S_s, S_t its partial derivatives
// and a = S_s·S_s, b = S_s·S_t, c = S_t·S_t:
//   L² stretch  √((a + c)/2)        (Sander et al. 2001: the root-mean-square stretch over all directions)
//   L∞ stretch  Γ = √(((a + c) + √((a − c)² + 4b²))/2)   (the largest singular value)
//   shear       |b| / √(a·c)         (ABF++ reports an L² shear next to Sander's stretch: the cosine of
//                                     the angle between S_s and S_t, the images of the texture axes on the
//                                     surface; 0 when they stay orthogonal. Written from the paper's
//                                     description as recalled: the text was not at hand to re-check here.)
struct TriangleDistortion {
  double l2_stretch = 0.0;
  double linf_stretch = 0.0;
  double shear = 0.0;
  double aspect = 1.0;        // σ1/σ2 of the map: 1 for a conformal one
  double uv_area = 0.0;       // signed, counter-clockwise positive (u right, v up)
  double surface_area = 0.0;  // 3D
  bool flipped = false;       // uv_area < 0 (and not degenerate)
  bool degenerate = false;    // |uv_area| negligible: stretch undefined
};

// `uv` are texture-domain positions with v up (counter-clockwise = front). `domain_scale` multiplies them
// first (used for the area normalisation below).
TriangleDistortion triangle_distortion(Vec3 q0, Vec3 q1, Vec3 q2, Point uv0, Point uv1, Point uv2,
                                       double domain_scale = 1.0);

struct UvMetrics {
  // Mesh norms over non-degenerate triangles, weighted by 3D area (Sander et al. 2001: L²(M) =
  // √(Σ L²(T)² A'(T) / Σ A'(T))), with the texture domain scaled so that its total area equals the surface
  // area: scale-free, 1 (stretch) and 0 (shear) for an isometry.
  double l2_stretch = 0.0;
  double linf_stretch = 0.0;  // max Γ over triangles, same normalisation
  double l2_shear = 0.0;      // √(Σ shear(T)² A'(T) / Σ A'(T))
  double max_aspect = 1.0;    // max σ1/σ2 over triangles
  int flipped = 0;
  int degenerate = 0;
  double uv_area = 0.0;  // Σ |uv_area| before normalisation
  double surface_area = 0.0;
  std::vector<TriangleDistortion> per_triangle;  // normalised, in face order; filled on request
};

// UV triangles whose |area| is below this fraction of the mean |area| (or of their longest edge squared)
// count as degenerate.
inline constexpr double kDegenerateUvFraction = 1e-12;

UvMetrics uv_metrics(const TriangleMesh& mesh, std::span<const Point> uv, bool keep_per_triangle = false);

}  // namespace texwarp::mesh
