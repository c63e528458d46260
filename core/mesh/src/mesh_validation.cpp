// Mesh validation: see mesh_validation.hpp.
#include "texwarp/mesh/mesh_validation.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <vector>

#include "texwarp/mesh/edge_key.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {
namespace {

class Namer {
 public:
  explicit Namer(const MeshSource& source) : source_(source) {}
  std::string face(int f) const {
    return source_.json_path ? source_.json_path->key("triangles").index(static_cast<std::size_t>(f)).str()
                             : "face " + std::to_string(f);
  }
  std::string vertex(int v) const {
    return source_.json_path ? source_.json_path->key("vertices").index(static_cast<std::size_t>(v)).str()
                             : "vertex " + std::to_string(v);
  }
  [[noreturn]] void fail(const std::string& what) const { throw InputError(source_.where, what); }

 private:
  const MeshSource& source_;
};

std::string corners(const Face& f) {
  return "(" + std::to_string(f[0]) + ", " + std::to_string(f[1]) + ", " + std::to_string(f[2]) + ")";
}

}  // namespace

void validate_mesh(const TriangleMesh& mesh, const MeshSource& source) {
  const Namer name(source);
  const int nv = mesh.vertex_count();
  const int nf = mesh.face_count();
  if (nf == 0) name.fail("the mesh has no faces");

  for (int v = 0; v < nv; ++v) {
    if (!is_finite(mesh.vertices[v])) name.fail(name.vertex(v) + " has a non-finite coordinate (NaN or infinity)");
  }
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.faces[f][k];
      if (v < 0 || v >= nv) {
        name.fail(name.face(f) + " refers to vertex " + std::to_string(v) + ", but the mesh has " + std::to_string(nv) +
                  " vertices (ids 0.." + std::to_string(nv - 1) + ")");
      }
    }
  }
  for (int f = 0; f < nf; ++f) {
    const Face& t = mesh.faces[f];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      name.fail(name.face(f) + " is degenerate: it uses a vertex twice " + corners(t));
    }
    const Vec3 a = mesh.vertices[t[0]];
    const Vec3 b = mesh.vertices[t[1]];
    const Vec3 c = mesh.vertices[t[2]];
    const double longest = std::max({dot(b - a, b - a), dot(c - b, c - b), dot(a - c, a - c)});
    if (norm(doubled_normal(a, b, c)) <= kDegenerateAreaFraction * longest) {
      name.fail(name.face(f) + " is degenerate: its area is zero (corners " + corners(t) +
                " coincide or are collinear)");
    }
  }
  {
    std::map<std::array<int, 3>, int> seen;
    for (int f = 0; f < nf; ++f) {
      std::array<int, 3> key = mesh.faces[f];
      std::sort(key.begin(), key.end());
      const auto [it, inserted] = seen.emplace(key, f);
      if (!inserted) {
        name.fail(name.face(it->second) + " and " + name.face(f) + " are duplicates: both use vertices " +
                  corners(key));
      }
    }
  }
  struct EdgeUse {
    int count = 0;
    int faces[2] = {-1, -1};
    int forward = 0;  // uses in the direction lo → hi
  };
  std::unordered_map<EdgeKey, EdgeUse> edges;
  edges.reserve(static_cast<std::size_t>(nf) * 2);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces[f][k];
      const int b = mesh.faces[f][(k + 1) % 3];
      EdgeUse& use = edges[edge_key(a, b)];
      if (use.count < 2) use.faces[use.count] = f;
      ++use.count;
      if (a < b) ++use.forward;
      if (use.count > 2) {
        name.fail("non-manifold edge (" + std::to_string(std::min(a, b)) + ", " + std::to_string(std::max(a, b)) +
                  "): shared by more than two faces (" + name.face(use.faces[0]) + ", " + name.face(use.faces[1]) +
                  ", " + name.face(f) + ")");
      }
    }
  }
  for (int f = 0; f < nf; ++f) {  // in face order, so that the first offender is reported
    for (int k = 0; k < 3; ++k) {
      const EdgeKey key = edge_key(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3]);
      const EdgeUse& use = edges.at(key);
      if (use.count == 2 && use.forward != 1) {
        const auto [a, b] = edge_vertices(key);
        name.fail("inconsistent orientation: " + name.face(use.faces[0]) + " and " + name.face(use.faces[1]) +
                  " both run along edge (" + std::to_string(a) + ", " + std::to_string(b) +
                  ") in the same direction (one of them is flipped; make the winding consistent)");
      }
    }
  }
  std::vector<char> used(static_cast<std::size_t>(nv), 0);
  for (const Face& t : mesh.faces) {
    for (int v : t) used[v] = 1;
  }
  for (int v = 0; v < nv; ++v) {
    if (!used[v]) name.fail(name.vertex(v) + " is not used by any face (unreferenced vertex)");
  }
}

}  // namespace texwarp::mesh
