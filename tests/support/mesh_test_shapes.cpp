// Generated test meshes: see mesh_test_shapes.hpp.
#include "mesh_test_shapes.hpp"

#include <cmath>
#include <numbers>
#include <random>

namespace texwarp::mesh::testing {
namespace {

// Quad a b c d (counter-clockwise) as two triangles.
void add_quad(TriangleMesh& m, int a, int b, int c, int d) {
  m.faces.push_back({a, b, c});
  m.faces.push_back({a, c, d});
}

}  // namespace

TriangleMesh flat_grid(int nx, int ny, double step, double jitter, std::uint32_t seed) {
  TriangleMesh m;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter * step, jitter * step);
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const bool interior = i > 0 && j > 0 && i < nx && j < ny;
      const double dx = interior ? u(rng) : 0.0;
      const double dy = interior ? u(rng) : 0.0;
      m.vertices.push_back({i * step + dx, j * step + dy, 0.0});
    }
  }
  const int w = nx + 1;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) add_quad(m, j * w + i, j * w + i + 1, (j + 1) * w + i + 1, (j + 1) * w + i);
  }
  return m;
}

TriangleMesh cylinder_strip(double radius, double span_rad, double height, int n_around, int n_up) {
  TriangleMesh m;
  for (int j = 0; j <= n_up; ++j) {
    for (int i = 0; i <= n_around; ++i) {
      const double theta = -0.5 * span_rad + span_rad * i / n_around;
      m.vertices.push_back({radius * std::sin(theta), height * j / n_up, radius * std::cos(theta)});
    }
  }
  const int w = n_around + 1;
  // Outside normal (sin θ, 0, cos θ): with θ increasing along +x and y up, (i, j) → (i+1, j) → (i+1, j+1) is
  // counter-clockwise seen from outside.
  for (int j = 0; j < n_up; ++j) {
    for (int i = 0; i < n_around; ++i) add_quad(m, j * w + i, j * w + i + 1, (j + 1) * w + i + 1, (j + 1) * w + i);
  }
  return m;
}

TriangleMesh sphere_cap(double max_polar_rad, int rings, int segments) {
  TriangleMesh m;
  m.vertices.push_back({0.0, 0.0, 1.0});
  for (int r = 1; r <= rings; ++r) {
    const double polar = max_polar_rad * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double az = 2.0 * std::numbers::pi * s / segments;
      m.vertices.push_back({std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az), std::cos(polar)});
    }
  }
  auto id = [segments](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.faces.push_back({0, id(1, s), id(1, s + 1)});
  for (int r = 1; r < rings; ++r) {
    for (int s = 0; s < segments; ++s) add_quad(m, id(r, s), id(r + 1, s), id(r + 1, s + 1), id(r, s + 1));
  }
  return m;
}

TriangleMesh height_field(int n, double step, double amplitude, double wavelength) {
  TriangleMesh m = flat_grid(n, n, step);
  const double k = 2.0 * std::numbers::pi / wavelength;
  for (Vec3& v : m.vertices) v.z = amplitude * std::sin(k * v.x) * std::cos(k * v.y);
  return m;
}

TriangleMesh torus(double major, double minor, int nu, int nv) {
  TriangleMesh m;
  for (int i = 0; i < nu; ++i) {
    const double u = 2.0 * std::numbers::pi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double v = 2.0 * std::numbers::pi * j / nv;
      m.vertices.push_back({(major + minor * std::cos(v)) * std::cos(u), (major + minor * std::cos(v)) * std::sin(u),
                            minor * std::sin(v)});
    }
  }
  auto id = [nu, nv](int i, int j) { return (i % nu) * nv + (j % nv); };
  for (int i = 0; i < nu; ++i) {
    for (int j = 0; j < nv; ++j) add_quad(m, id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
  }
  return m;
}

TriangleMesh annulus(double inner, double outer, int segments) {
  TriangleMesh m;
  for (int s = 0; s < segments; ++s) {
    const double a = 2.0 * std::numbers::pi * s / segments;
    m.vertices.push_back({inner * std::cos(a), inner * std::sin(a), 0.0});
    m.vertices.push_back({outer * std::cos(a), outer * std::sin(a), 0.0});
  }
  for (int s = 0; s < segments; ++s) {
    const int i0 = 2 * s, o0 = 2 * s + 1, i1 = 2 * ((s + 1) % segments), o1 = i1 + 1;
    add_quad(m, i0, o0, o1, i1);
  }
  return m;
}

TriangleMesh octahedron() {
  TriangleMesh m;
  m.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

}  // namespace texwarp::mesh::testing
