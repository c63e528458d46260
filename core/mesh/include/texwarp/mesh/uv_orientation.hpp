// Whether a UV triangle keeps the front's orientation as the user receives it: positive in the doubles computed
// and still positive after each UV is written as a float32 (glTF, Blender's UV layers) or printed (OBJ, %.10g).
#pragma once

#include <algorithm>
#include <cmath>

#include "texwarp/core/point.hpp"

namespace texwarp::mesh {

// Doubled signed area of a texture-pixel triangle (y down) in the domain's orientation (v up): > 0 counter-clockwise.
inline double uv_doubled_area(Point a, Point b, Point c) {
  const Point e = b - a, f = c - a;
  return -(e.real() * f.imag() - e.imag() * f.real());
}

// True when the triangle a b c (texture pixels, y down, of a width × height texture) is counter-clockwise in UV
// space (v up) by more than any rounding of its written UVs can undo. A written coordinate u = x / width (or
// v = y / height, or 1 − y / height) is off by at most one float32 ulp of max(|u|, 1) + 1, i.e. δ pixels with
// δ = 2⁻²³ (max(|u|, |v|, 1) + 1) · max(width, height); moving each corner by up to δ per axis changes the doubled
// area by at most 2√2 δ (|b − a| + |c − a|) + 8δ². Also not degenerate: the area exceeds 1e-12 of the longest edge².
inline bool uv_triangle_positive(Point a, Point b, Point c, int width, int height) {
  const double size = std::max(width, height);
  double reach = 1.0;
  for (const Point p : {a, b, c}) reach = std::max({reach, std::abs(p.real()) / width, std::abs(p.imag()) / height});
  const double delta = std::ldexp(reach + 1.0, -23) * size;
  const double ab = std::abs(b - a), ac = std::abs(c - a), bc = std::abs(c - b);
  const double longest = std::max({ab, ac, bc});
  const double doubled = uv_doubled_area(a, b, c);
  return doubled > 2.0 * std::sqrt(2.0) * delta * (ab + ac) + 8.0 * delta * delta &&
         doubled > 1e-12 * longest * longest;
}

}  // namespace texwarp::mesh
