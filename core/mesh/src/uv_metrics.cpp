// Stretch and shear of a texture mapping: see uv_metrics.hpp.
#include "texwarp/mesh/uv_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "texwarp/mesh/triangle_geometry.hpp"

namespace texwarp::mesh {
namespace {

double cross2(Point a, Point b) { return a.real() * b.imag() - a.imag() * b.real(); }

}  // namespace

TriangleDistortion triangle_distortion(Vec3 q0, Vec3 q1, Vec3 q2, Point uv0, Point uv1, Point uv2,
                                       double domain_scale) {
  const Point p0 = domain_scale * uv0, p1 = domain_scale * uv1, p2 = domain_scale * uv2;
  TriangleDistortion t;
  t.surface_area = triangle_area(q0, q1, q2);
  t.uv_area = 0.5 * cross2(p1 - p0, p2 - p0);
  const double longest = std::max({std::norm(p1 - p0), std::norm(p2 - p1), std::norm(p0 - p2)});
  if (std::abs(2.0 * t.uv_area) <= kDegenerateUvFraction * longest || t.uv_area == 0.0) {
    t.degenerate = true;
    return t;
  }
  t.flipped = t.uv_area < 0.0;
  // Sander et al. 2001: S_s = (q0 (t1 − t2) + q1 (t2 − t0) + q2 (t0 − t1)) / 2A,
  //                                 S_t = (q0 (s2 − s1) + q1 (s0 − s2) + q2 (s1 − s0)) / 2A.
  const double s0 = p0.real(), s1 = p1.real(), s2 = p2.real();
  const double t0 = p0.imag(), t1 = p1.imag(), t2 = p2.imag();
  const double a2 = 2.0 * t.uv_area;
  const Vec3 ss = (q0 * (t1 - t2) + q1 * (t2 - t0) + q2 * (t0 - t1)) / a2;
  const Vec3 st = (q0 * (s2 - s1) + q1 * (s0 - s2) + q2 * (s1 - s0)) / a2;
  const double a = dot(ss, ss), b = dot(ss, st), c = dot(st, st);
  t.l2_stretch = std::sqrt(0.5 * (a + c));
  const double spread = std::sqrt((a - c) * (a - c) + 4.0 * b * b);
  t.linf_stretch = std::sqrt(0.5 * ((a + c) + spread));
  const double least = 0.5 * ((a + c) - spread);  // σ2², rounded at most to 0 when the map is nearly singular
  t.aspect = least > 0.0 ? std::sqrt(0.5 * ((a + c) + spread) / least) : std::numeric_limits<double>::infinity();
  t.shear = std::abs(b) / std::sqrt(a * c);
  return t;
}

UvMetrics uv_metrics(const TriangleMesh& mesh, std::span<const Point> uv, bool keep_per_triangle) {
  UvMetrics m;
  const int nf = mesh.face_count();
  // First pass: areas, to normalise the domain (Σ|uv area| = Σ surface area over non-degenerate triangles).
  std::vector<TriangleDistortion> raw(static_cast<std::size_t>(nf));
  double mean_abs = 0.0;
  for (int f = 0; f < nf; ++f) {
    const Face& t = mesh.faces[f];
    raw[f] = triangle_distortion(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], uv[t[0]], uv[t[1]],
                                 uv[t[2]]);
    mean_abs += std::abs(raw[f].uv_area);
  }
  mean_abs /= std::max(1, nf);
  double uv_area = 0.0, surface_area = 0.0;
  for (int f = 0; f < nf; ++f) {
    if (std::abs(raw[f].uv_area) <= kDegenerateUvFraction * mean_abs) raw[f].degenerate = true;
    if (raw[f].degenerate) continue;
    uv_area += std::abs(raw[f].uv_area);
    surface_area += raw[f].surface_area;
  }
  m.uv_area = uv_area;
  const double scale = uv_area > 0.0 ? std::sqrt(surface_area / uv_area) : 1.0;
  double stretch2 = 0.0, shear2 = 0.0;
  m.surface_area = 0.0;
  if (keep_per_triangle) m.per_triangle.resize(static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f) {
    TriangleDistortion d = raw[f];
    if (!d.degenerate) {
      const Face& t = mesh.faces[f];
      d = triangle_distortion(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], uv[t[0]], uv[t[1]],
                              uv[t[2]], scale);
      stretch2 += d.l2_stretch * d.l2_stretch * d.surface_area;
      shear2 += d.shear * d.shear * d.surface_area;
      m.surface_area += d.surface_area;
      m.linf_stretch = std::max(m.linf_stretch, d.linf_stretch);
      m.max_aspect = std::max(m.max_aspect, d.aspect);
      if (d.flipped) ++m.flipped;
    } else {
      d.degenerate = true;
      ++m.degenerate;
    }
    if (keep_per_triangle) m.per_triangle[f] = d;
  }
  if (m.surface_area > 0.0) {
    m.l2_stretch = std::sqrt(stretch2 / m.surface_area);
    m.l2_shear = std::sqrt(shear2 / m.surface_area);
  }
  return m;
}

}  // namespace texwarp::mesh
