// Free-boundary LSCM: see lscm.hpp.
#include "texwarp/mesh/lscm.hpp"

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Sparse>

#include "sparse_cholesky.hpp"
#include "texwarp/core/numerical_error.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"

namespace texwarp::mesh {
namespace {

// An entry of LSCM's normal matrix this small against its row's and column's diagonal is a sum that cancelled
// (rounding is ~1e-16 of it).
constexpr double kCancelledCoupling = 1e-12;

// The triangle in its own orthonormal frame (x along edge 0→1, y towards corner 2): corner positions, area,
// and the gradients of the three hat functions, ∇φ_j = rot90(z_{j+2} − z_{j+1}) / (2A).
struct LocalTriangle {
  double area = 0.0;
  std::array<double, 3> gx{};
  std::array<double, 3> gy{};
};

LocalTriangle local_triangle(Vec3 p0, Vec3 p1, Vec3 p2) {
  const Vec3 e1 = p1 - p0;
  const Vec3 e2 = p2 - p0;
  const double l1 = norm(e1);
  const Vec3 x = e1 / l1;
  const Vec3 n = cross(e1, e2);
  const Vec3 y = cross(n, e1) / (norm(n) * l1);
  const std::array<double, 3> zx{0.0, l1, dot(e2, x)};
  const std::array<double, 3> zy{0.0, 0.0, dot(e2, y)};
  LocalTriangle t;
  t.area = 0.5 * (zx[1] * zy[2] - zx[2] * zy[1]);
  for (int j = 0; j < 3; ++j) {
    const int a = (j + 1) % 3;
    const int b = (j + 2) % 3;
    // rot90 of (z_b − z_a): (−dy, dx)
    t.gx[j] = -(zy[b] - zy[a]) / (2.0 * t.area);
    t.gy[j] = (zx[b] - zx[a]) / (2.0 * t.area);
  }
  return t;
}

}  // namespace

double lscm_energy(const TriangleMesh& mesh, std::span<const Point> positions) {
  double energy = 0.0;
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Face& face = mesh.faces[f];
    const LocalTriangle t = local_triangle(mesh.vertices[face[0]], mesh.vertices[face[1]], mesh.vertices[face[2]]);
    double ux = 0.0, uy = 0.0, vx = 0.0, vy = 0.0;
    for (int j = 0; j < 3; ++j) {
      const Point p = positions[face[j]];
      ux += p.real() * t.gx[j];
      uy += p.real() * t.gy[j];
      vx += p.imag() * t.gx[j];
      vy += p.imag() * t.gy[j];
    }
    energy += t.area * ((ux - vy) * (ux - vy) + (uy + vx) * (uy + vx));
  }
  return energy;
}

std::array<int, 2> lscm_pin_vertices(const TriangleMesh& mesh, std::span<const int> boundary) {
  std::vector<int> candidates(boundary.begin(), boundary.end());
  if (candidates.empty()) {
    for (int v = 0; v < mesh.vertex_count(); ++v) candidates.push_back(v);
  }
  auto farthest = [&](int from) {
    int best = candidates.front();
    double best_d = -1.0;
    for (int v : candidates) {
      const double d = norm(mesh.vertices[v] - mesh.vertices[from]);
      if (d > best_d) {
        best_d = d;
        best = v;
      }
    }
    return best;
  };
  const int a = farthest(candidates.front());
  const int b = farthest(a);
  return {a, b};
}

LscmEmbedding lscm_embedding(const TriangleMesh& mesh, std::span<const int> boundary,
                             std::optional<std::array<int, 2>> pinned) {
  const int n = mesh.vertex_count();
  LscmEmbedding out;
  out.pinned = pinned ? *pinned : lscm_pin_vertices(mesh, boundary);
  const int p0 = out.pinned[0];
  const int p1 = out.pinned[1];
  if (p0 == p1) throw NumericalError("LSCM needs two distinct pinned vertices");
  const double span = norm(mesh.vertices[p1] - mesh.vertices[p0]);
  const Point pin_pos[2] = {Point(0.0, 0.0), Point(span, 0.0)};

  // Unknowns: u then v of every free vertex. free_index[v] = its column, −1 for a pinned vertex.
  std::vector<int> free_index(static_cast<std::size_t>(n), -1);
  int m = 0;
  for (int v = 0; v < n; ++v) {
    if (v != p0 && v != p1) free_index[v] = m++;
  }
  // Rows per triangle: √A·(u_x − v_y) and √A·(u_y + v_x), linear in (u_j, v_j).
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(mesh.face_count()) * 12);
  const Eigen::Index rows = Eigen::Index{2} * mesh.face_count();
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(rows);
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Face& face = mesh.faces[f];
    const LocalTriangle t = local_triangle(mesh.vertices[face[0]], mesh.vertices[face[1]], mesh.vertices[face[2]]);
    const double w = std::sqrt(t.area);
    const int r0 = 2 * f;
    const int r1 = 2 * f + 1;
    for (int j = 0; j < 3; ++j) {
      const int v = face[j];
      // coefficients of u_j and v_j in the two rows
      const double cu0 = w * t.gx[j], cv0 = -w * t.gy[j];
      const double cu1 = w * t.gy[j], cv1 = w * t.gx[j];
      if (free_index[v] >= 0) {
        const int cu = free_index[v];
        const int cv = m + free_index[v];
        triplets.emplace_back(r0, cu, cu0);
        triplets.emplace_back(r0, cv, cv0);
        triplets.emplace_back(r1, cu, cu1);
        triplets.emplace_back(r1, cv, cv1);
      } else {
        const Point p = pin_pos[v == p0 ? 0 : 1];
        rhs[r0] -= cu0 * p.real() + cv0 * p.imag();
        rhs[r1] -= cu1 * p.real() + cv1 * p.imag();
      }
    }
  }
  Eigen::SparseMatrix<double> a(rows, Eigen::Index{2} * m);
  a.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::SparseMatrix<double> normal = a.transpose() * a;
  // The u–v coupling of an interior edge is ±½ from each of its two triangles and cancels (it survives only on the
  // boundary), but the rounded sum stays a stored entry: left in, it couples u and v at every vertex and the
  // factor costs several times as much. Entries at rounding level against their diagonal are dropped.
  const Eigen::VectorXd diagonal = normal.diagonal();
  normal.prune([&diagonal](Eigen::Index r, Eigen::Index c, double value) {
    return r == c || std::abs(value) > kCancelledCoupling * std::sqrt(diagonal[r] * diagonal[c]);
  });
  const Eigen::VectorXd b = a.transpose() * rhs;
  SparseCholesky solver(normal);
  if (solver.info() != Eigen::Success) {
    throw NumericalError("LSCM: the normal equations could not be factorised (is the region connected?)");
  }
  const Eigen::VectorXd x = solver.solve(b);
  if (solver.info() != Eigen::Success || !x.allFinite()) {
    throw NumericalError("LSCM: the sparse solve failed");
  }
  out.positions.assign(static_cast<std::size_t>(n), Point());
  for (int v = 0; v < n; ++v) {
    if (free_index[v] >= 0) {
      out.positions[v] = Point(x[free_index[v]], x[m + free_index[v]]);
    } else {
      out.positions[v] = pin_pos[v == p0 ? 0 : 1];
    }
  }
  out.energy = lscm_energy(mesh, out.positions);
  return out;
}

}  // namespace texwarp::mesh
