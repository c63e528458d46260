// Mesh topology: see mesh_topology.hpp.
#include "texwarp/mesh/mesh_topology.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <unordered_map>

namespace texwarp::mesh {
namespace {

std::uint64_t directed_key(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  std::size_t find(std::size_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(std::size_t a, std::size_t b) { parent_[find(a)] = find(b); }

 private:
  std::vector<std::size_t> parent_;
};

int corner_of(const Face& f, int v) { return f[0] == v ? 0 : (f[1] == v ? 1 : 2); }

}  // namespace

MeshTopology analyse_topology(const TriangleMesh& mesh) {
  const int nf = mesh.face_count();
  MeshTopology topo;
  topo.neighbour.assign(static_cast<std::size_t>(nf), {-1, -1, -1});

  std::unordered_map<std::uint64_t, int> half_edges;  // directed (a, b) → face
  half_edges.reserve(static_cast<std::size_t>(nf) * 3);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) half_edges[directed_key(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3])] = f;
  }
  int interior_half_edges = 0;
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const auto it = half_edges.find(directed_key(mesh.faces[f][(k + 1) % 3], mesh.faces[f][k]));
      if (it != half_edges.end()) {
        topo.neighbour[f][k] = it->second;
        ++interior_half_edges;
      }
    }
  }
  const int boundary_half_edges = 3 * nf - interior_half_edges;
  topo.edge_count = interior_half_edges / 2 + boundary_half_edges;

  // Components: breadth-first over neighbours.
  topo.component.assign(static_cast<std::size_t>(nf), -1);
  std::vector<int> queue;
  for (int seed = 0; seed < nf; ++seed) {
    if (topo.component[seed] >= 0) continue;
    const int id = topo.component_count++;
    topo.component[seed] = id;
    queue.assign(1, seed);
    while (!queue.empty()) {
      const int f = queue.back();
      queue.pop_back();
      for (int g : topo.neighbour[f]) {
        if (g >= 0 && topo.component[g] < 0) {
          topo.component[g] = id;
          queue.push_back(g);
        }
      }
    }
  }

  // Fans: corners (f, k) joined across the two edges of f that meet at corner k.
  UnionFind fans(static_cast<std::size_t>(nf) * 3);
  auto corner = [](int f, int k) { return std::size_t{3} * static_cast<std::size_t>(f) + static_cast<std::size_t>(k); };
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int g = topo.neighbour[f][k];
      if (g < f) continue;  // each interior edge once (g = −1 skipped too)
      const int a = mesh.faces[f][k];
      const int b = mesh.faces[f][(k + 1) % 3];
      fans.unite(corner(f, k), corner(g, corner_of(mesh.faces[g], a)));
      fans.unite(corner(f, (k + 1) % 3), corner(g, corner_of(mesh.faces[g], b)));
    }
  }
  std::unordered_map<int, std::size_t> first_root;
  std::vector<char> pinched(static_cast<std::size_t>(mesh.vertex_count()), 0);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.faces[f][k];
      const std::size_t root = fans.find(corner(f, k));
      const auto [it, inserted] = first_root.emplace(v, root);
      if (!inserted && it->second != root) pinched[v] = 1;
    }
  }
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    if (pinched[v]) topo.pinched_vertices.push_back(v);
  }

  // Boundary loops: follow the boundary half-edges a → b (a face's edge with no face across).
  std::unordered_map<int, std::vector<int>> next;  // a → every b
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      if (topo.neighbour[f][k] < 0) next[mesh.faces[f][k]].push_back(mesh.faces[f][(k + 1) % 3]);
    }
  }
  std::vector<int> starts;
  starts.reserve(next.size());
  for (const auto& [a, bs] : next) starts.push_back(a);
  std::sort(starts.begin(), starts.end());
  for (int start : starts) {
    if (next[start].empty()) continue;
    std::vector<int> loop;
    int v = start;
    while (true) {
      auto& candidates = next[v];
      if (candidates.empty()) break;
      loop.push_back(v);
      const int w = candidates.back();
      candidates.pop_back();
      v = w;
      if (v == start) break;
    }
    topo.boundary_loops.push_back(std::move(loop));
  }
  return topo;
}

}  // namespace texwarp::mesh
