// Flipped embeddings and their repair: see embedding_repair.hpp.
#include "texwarp/mesh/embedding_repair.hpp"

#include <cmath>
#include <numbers>

#include <Eigen/Sparse>
#include <Eigen/SparseLU>

#include "texwarp/core/numerical_error.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"

namespace texwarp::mesh {
namespace {

double signed_area(Point a, Point b, Point c) {
  const Point u = b - a, v = c - a;
  return 0.5 * (u.real() * v.imag() - u.imag() * v.real());
}

// The angle at `at` between the 3D directions to a and b.
double corner_angle(Vec3 at, Vec3 a, Vec3 b) {
  const Vec3 u = a - at, v = b - at;
  return std::atan2(norm(cross(u, v)), dot(u, v));
}

}  // namespace

std::vector<int> embedding_flipped_faces(const TriangleMesh& mesh, std::span<const Point> positions) {
  std::vector<double> area(static_cast<std::size_t>(mesh.face_count()));
  int positive = 0;
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Face& t = mesh.faces[f];
    area[f] = signed_area(positions[t[0]], positions[t[1]], positions[t[2]]);
    positive += area[f] > 0.0 ? 1 : 0;
  }
  const double sign = 2 * positive >= mesh.face_count() ? 1.0 : -1.0;
  std::vector<int> flipped;
  for (int f = 0; f < mesh.face_count(); ++f) {
    if (!(sign * area[f] > 0.0)) flipped.push_back(f);
  }
  return flipped;
}

std::vector<Point> mean_value_embedding(const TriangleMesh& mesh, std::span<const int> boundary) {
  const int n = mesh.vertex_count();
  if (boundary.size() < 3) throw NumericalError("mean-value embedding: the boundary has fewer than 3 vertices");
  std::vector<Point> out(static_cast<std::size_t>(n));
  std::vector<int> index(static_cast<std::size_t>(n), 0);  // ≥ 0: interior unknown; −1: on the boundary
  // The boundary on the unit circle, counter-clockwise, spaced by 3D edge length.
  double perimeter = 0.0;
  std::vector<double> at(boundary.size() + 1, 0.0);
  for (std::size_t i = 0; i < boundary.size(); ++i) {
    perimeter += norm(mesh.vertices[boundary[(i + 1) % boundary.size()]] - mesh.vertices[boundary[i]]);
    at[i + 1] = perimeter;
  }
  for (std::size_t i = 0; i < boundary.size(); ++i) {
    out[boundary[i]] = std::polar(1.0, 2.0 * std::numbers::pi * at[i] / perimeter);
    index[boundary[i]] = -1;
  }
  int m = 0;
  for (int v = 0; v < n; ++v) {
    if (index[v] >= 0) index[v] = m++;
  }
  // w_ij = (tan(α_ij/2) + tan(β_ij/2)) / |x_j − x_i|, summed over the faces around edge ij (the two angles at i
  // next to the edge); row i: Σ_j w_ij (x_i − x_j) = 0.
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd bx = Eigen::VectorXd::Zero(m), by = Eigen::VectorXd::Zero(m);
  for (const Face& t : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      const int i = t[k], j = t[(k + 1) % 3], l = t[(k + 2) % 3];
      if (index[i] < 0) continue;
      const Vec3 xi = mesh.vertices[i], xj = mesh.vertices[j], xl = mesh.vertices[l];
      const double half_tan = std::tan(0.5 * corner_angle(xi, xj, xl));
      for (int other : {j, l}) {  // the angle at i is next to both edges i–j and i–l
        const double w = half_tan / norm(mesh.vertices[other] - xi);
        triplets.emplace_back(index[i], index[i], w);
        if (index[other] >= 0) {
          triplets.emplace_back(index[i], index[other], -w);
        } else {
          bx[index[i]] += w * out[other].real();
          by[index[i]] += w * out[other].imag();
        }
      }
    }
  }
  if (m > 0) {
    Eigen::SparseMatrix<double> a(m, m);
    a.setFromTriplets(triplets.begin(), triplets.end());
    Eigen::SparseLU<Eigen::SparseMatrix<double>> solver;
    solver.compute(a);
    if (solver.info() != Eigen::Success) throw NumericalError("mean-value embedding: the system is singular");
    const Eigen::VectorXd x = solver.solve(bx), y = solver.solve(by);
    if (solver.info() != Eigen::Success || !x.allFinite() || !y.allFinite()) {
      throw NumericalError("mean-value embedding: the sparse solve failed");
    }
    for (int v = 0; v < n; ++v) {
      if (index[v] >= 0) out[v] = Point(x[index[v]], y[index[v]]);
    }
  }
  double plane = 0.0, surface = 0.0;
  for (const Face& t : mesh.faces) {
    plane += std::abs(signed_area(out[t[0]], out[t[1]], out[t[2]]));
    surface += triangle_area(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
  }
  const double scale = plane > 0.0 ? std::sqrt(surface / plane) : 1.0;
  for (Point& p : out) p *= scale;
  return out;
}

EmbeddingRepair repair_embedding(const TriangleMesh& mesh, std::span<const int> boundary,
                                 std::vector<Point> positions) {
  EmbeddingRepair r;
  r.flipped_faces = embedding_flipped_faces(mesh, positions);
  if (r.flipped_faces.empty()) {
    r.positions = std::move(positions);
    return r;
  }
  r.positions = mean_value_embedding(mesh, boundary);
  r.method = proto::EmbeddingMethod::kMeanValue;
  return r;
}

}  // namespace texwarp::mesh
