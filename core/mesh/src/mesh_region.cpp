// Region extraction and the disk check: see mesh_region.hpp.
#include "texwarp/mesh/mesh_region.hpp"

#include <algorithm>
#include <limits>
#include <queue>
#include <unordered_map>
#include <unordered_set>

#include "texwarp/mesh/edge_key.hpp"
#include "texwarp/mesh/mesh_topology.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {
namespace {

std::string plural(std::size_t n, const std::string& one, const std::string& many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

std::string list_ids(const std::vector<int>& ids, std::size_t max_shown = 8) {
  std::string out;
  for (std::size_t i = 0; i < ids.size() && i < max_shown; ++i) out += (i ? ", " : "") + std::to_string(ids[i]);
  if (ids.size() > max_shown) out += ", ...";
  return out;
}

// Vertex adjacency with edge lengths, for Dijkstra.
std::vector<std::vector<std::pair<int, double>>> vertex_graph(const TriangleMesh& mesh) {
  std::vector<std::vector<std::pair<int, double>>> graph(static_cast<std::size_t>(mesh.vertex_count()));
  std::unordered_set<EdgeKey> seen;
  for (const Face& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      const int a = f[k];
      const int b = f[(k + 1) % 3];
      if (!seen.insert(edge_key(a, b)).second) continue;
      const double length = norm(mesh.vertices[a] - mesh.vertices[b]);
      graph[a].emplace_back(b, length);
      graph[b].emplace_back(a, length);
    }
  }
  return graph;
}

// Shortest edge path a → b (both included); empty when b cannot be reached.
std::vector<int> shortest_path(const std::vector<std::vector<std::pair<int, double>>>& graph, int a, int b) {
  const std::size_t n = graph.size();
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  std::vector<int> prev(n, -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
  dist[a] = 0.0;
  heap.emplace(0.0, a);
  while (!heap.empty()) {
    const auto [d, v] = heap.top();
    heap.pop();
    if (d > dist[v]) continue;
    if (v == b) break;
    for (const auto& [w, length] : graph[v]) {
      if (d + length < dist[w]) {
        dist[w] = d + length;
        prev[w] = v;
        heap.emplace(dist[w], w);
      }
    }
  }
  if (prev[b] < 0 && a != b) return {};
  std::vector<int> path;
  for (int v = b; v != -1; v = prev[v]) path.push_back(v);
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace

MeshRegion disk_region(const TriangleMesh& mesh, std::vector<int> faces, const proto::InputLocation& where,
                       const std::string& subject) {
  if (faces.empty()) throw InputError(where, subject + " has no faces");
  std::sort(faces.begin(), faces.end());
  MeshRegion region;
  region.faces = std::move(faces);
  region.local_vertex.assign(static_cast<std::size_t>(mesh.vertex_count()), -1);
  region.local_face.assign(static_cast<std::size_t>(mesh.face_count()), -1);
  for (int f : region.faces) {
    for (int v : mesh.faces[f]) region.local_vertex[v] = 0;
  }
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    if (region.local_vertex[v] >= 0) {
      region.local_vertex[v] = region.vertex_count();
      region.vertices.push_back(v);
      region.local.vertices.push_back(mesh.vertices[v]);
    }
  }
  for (int i = 0; i < region.face_count(); ++i) {
    const int f = region.faces[i];
    region.local_face[f] = i;
    const Face& t = mesh.faces[f];
    region.local.faces.push_back({region.local_vertex[t[0]], region.local_vertex[t[1]], region.local_vertex[t[2]]});
  }

  const MeshTopology topo = analyse_topology(region.local);
  if (topo.component_count > 1) {
    std::vector<int> sizes(static_cast<std::size_t>(topo.component_count), 0);
    std::vector<int> first(static_cast<std::size_t>(topo.component_count), -1);
    for (int i = 0; i < region.face_count(); ++i) {
      const int c = topo.component[i];
      if (sizes[c]++ == 0) first[c] = region.faces[i];
    }
    std::string parts;
    for (int c = 0; c < topo.component_count && c < 4; ++c) {
      parts += (c ? "; " : "") + plural(static_cast<std::size_t>(sizes[c]), "face", "faces") + " from face " +
               std::to_string(first[c]);
    }
    if (topo.component_count > 4) parts += "; ...";
    throw InputError(where, subject + " is not a single disk: it has " + std::to_string(topo.component_count) +
                                " connected components (" + parts + "); it must be one piece");
  }
  if (!topo.pinched_vertices.empty()) {
    std::vector<int> ids;
    for (int v : topo.pinched_vertices) ids.push_back(region.vertices[v]);
    throw InputError(where, subject + " is not a disk: it touches itself at " +
                                plural(ids.size(), "vertex", "vertices") + " (" + list_ids(ids) +
                                ") whose faces form separate fans");
  }
  const int chi = topo.euler_characteristic(region.vertex_count());
  const int loops = static_cast<int>(topo.boundary_loops.size());
  const int genus = (2 - chi - loops) / 2;
  const std::string euler = "Euler characteristic V − E + F = " + std::to_string(region.vertex_count()) + " − " +
                            std::to_string(topo.edge_count) + " + " + std::to_string(region.face_count()) + " = " +
                            std::to_string(chi);
  if (loops == 0) {
    throw InputError(where, subject + " is closed (no boundary; genus " + std::to_string(genus) + ", " + euler +
                                "): a disk needs one boundary loop; give a region that cuts it open (a face set "
                                "or a closed boundary curve with a seed face)");
  }
  if (genus > 0) {
    throw InputError(where, subject + " is not a disk: it has genus " + std::to_string(genus) + " (" + euler + ", " +
                                plural(static_cast<std::size_t>(loops), "boundary loop", "boundary loops") +
                                "; a disk has genus 0 and χ = 1): cut it so that it has no handles");
  }
  if (loops > 1) {
    std::string holes;
    for (int i = 0; i < loops && i < 4; ++i) {
      const auto& loop = topo.boundary_loops[i];
      holes += (i ? "; " : "") + plural(loop.size(), "vertex", "vertices") + " from vertex " +
               std::to_string(region.vertices[loop.front()]);
    }
    if (loops > 4) holes += "; ...";
    throw InputError(where, subject + " is not a disk: it has " + std::to_string(loops) + " boundary loops (" + holes +
                                "), i.e. " + plural(static_cast<std::size_t>(loops - 1), "hole", "holes") +
                                "; a disk has exactly one boundary loop");
  }
  region.boundary = topo.boundary_loops.front();
  return region;
}

MeshRegion whole_mesh_region(const TriangleMesh& mesh, const proto::InputLocation& where) {
  std::vector<int> faces(static_cast<std::size_t>(mesh.face_count()));
  for (int f = 0; f < mesh.face_count(); ++f) faces[f] = f;
  return disk_region(mesh, std::move(faces), where, "the mesh");
}

std::vector<int> close_vertex_curve(const TriangleMesh& mesh, std::span<const int> curve,
                                    const proto::InputLocation& where) {
  for (std::size_t i = 0; i < curve.size(); ++i) {
    if (curve[i] < 0 || curve[i] >= mesh.vertex_count()) {
      throw InputError(where, "boundary[" + std::to_string(i) + "] = " + std::to_string(curve[i]) +
                                  " is not a vertex id (the mesh has " + std::to_string(mesh.vertex_count()) +
                                  " vertices)");
    }
  }
  std::vector<int> given(curve.begin(), curve.end());
  if (given.size() > 1 && given.front() == given.back()) given.pop_back();
  if (given.size() < 3) {
    throw InputError(where,
                     "the boundary curve needs at least 3 distinct vertices, got " + std::to_string(given.size()));
  }
  const auto graph = vertex_graph(mesh);
  std::vector<int> closed;
  for (std::size_t i = 0; i < given.size(); ++i) {
    const int a = given[i];
    const int b = given[(i + 1) % given.size()];
    if (a == b) {
      throw InputError(where, "boundary[" + std::to_string(i) + "] and the next entry are the same vertex " +
                                  std::to_string(a));
    }
    const std::vector<int> path = shortest_path(graph, a, b);
    if (path.empty()) {
      throw InputError(where, "boundary vertices " + std::to_string(a) + " and " + std::to_string(b) +
                                  " are not connected by any path of mesh edges");
    }
    closed.insert(closed.end(), path.begin(), path.end() - 1);  // b starts the next piece
  }
  std::unordered_map<int, std::size_t> seen;
  for (std::size_t i = 0; i < closed.size(); ++i) {
    const auto [it, inserted] = seen.emplace(closed[i], i);
    if (!inserted) {
      throw InputError(where, "the boundary curve passes vertex " + std::to_string(closed[i]) +
                                  " twice (after joining consecutive vertices by shortest edge paths): it must be a "
                                  "simple closed curve");
    }
  }
  if (closed.size() < 3) throw InputError(where, "the boundary curve needs at least 3 distinct vertices");
  return closed;
}

std::vector<int> faces_inside_curve(const TriangleMesh& mesh, std::span<const int> closed_curve, int seed_face,
                                    const proto::InputLocation& where) {
  if (seed_face < 0 || seed_face >= mesh.face_count()) {
    throw InputError(where, "seed_face " + std::to_string(seed_face) + " is not a face id (the mesh has " +
                                std::to_string(mesh.face_count()) + " faces)");
  }
  std::unordered_set<EdgeKey> cut;
  for (std::size_t i = 0; i < closed_curve.size(); ++i) {
    cut.insert(edge_key(closed_curve[i], closed_curve[(i + 1) % closed_curve.size()]));
  }
  const MeshTopology topo = analyse_topology(mesh);
  std::vector<char> inside(static_cast<std::size_t>(mesh.face_count()), 0);
  std::vector<int> stack{seed_face};
  inside[seed_face] = 1;
  std::vector<int> faces;
  while (!stack.empty()) {
    const int f = stack.back();
    stack.pop_back();
    faces.push_back(f);
    for (int k = 0; k < 3; ++k) {
      const int g = topo.neighbour[f][k];
      if (g < 0 || inside[g]) continue;
      if (cut.count(edge_key(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3]))) continue;
      inside[g] = 1;
      stack.push_back(g);
    }
  }
  if (static_cast<int>(faces.size()) == mesh.face_count() ||
      static_cast<int>(faces.size()) ==
          std::count(topo.component.begin(), topo.component.end(), topo.component[seed_face])) {
    throw InputError(where, "the boundary curve does not separate the surface: from seed_face " +
                                std::to_string(seed_face) +
                                " every face of its component is reachable without "
                                "crossing the curve");
  }
  std::sort(faces.begin(), faces.end());
  return faces;
}

}  // namespace texwarp::mesh
