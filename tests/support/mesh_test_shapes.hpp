// Generated meshes for the mesh tests and the mesh comparison table (bench/): flat grids, a cylinder strip
// (developable), a sphere cap and a bumpy height field (not developable), and meshes with one topological defect each.
#pragma once

#include <cstdint>

#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh::testing {

// (nx+1)·(ny+1) vertices on [0, nx·step] × [0, ny·step] in z = 0, vertex (i, j) at index j·(nx+1) + i,
// interior vertices jittered by up to `jitter`·step (deterministic for a seed); faces counter-clockwise
// seen from +z.
TriangleMesh flat_grid(int nx, int ny, double step = 1.0, double jitter = 0.0, std::uint32_t seed = 1);

// Vertices on the cylinder x² + z² = r² (x = r·sin θ, z = r·cos θ, θ ∈ [−span/2, span/2]), y ∈ [0, height];
// faces counter-clockwise seen from outside. Piecewise flat and intrinsically flat: developable.
TriangleMesh cylinder_strip(double radius, double span_rad, double height, int n_around, int n_up);

// The cap of the unit-radius sphere within polar angle max_polar of +z: rings × segments quads (a fan at
// the pole), counter-clockwise seen from outside.
TriangleMesh sphere_cap(double max_polar_rad, int rings, int segments);

// z = amplitude·sin(2π x / wavelength)·cos(2π y / wavelength) over flat_grid(n, n, step).
TriangleMesh height_field(int n, double step, double amplitude, double wavelength);

// A closed torus (genus 1), nu × nv quads split in two.
TriangleMesh torus(double major, double minor, int nu, int nv);

// A flat ring (annulus): one hole, two boundary loops.
TriangleMesh annulus(double inner, double outer, int segments);

// A closed octahedron (genus 0, no boundary).
TriangleMesh octahedron();

}  // namespace texwarp::mesh::testing
