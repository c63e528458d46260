// Refinement of a region so that no UV triangle flips and features are vertices: see mesh_refinement.hpp.
#include "texwarp/mesh/mesh_refinement.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <unordered_set>
#include <utility>

#include "texwarp/core/numerical_error.hpp"
#include "texwarp/mesh/uv_orientation.hpp"

namespace texwarp::mesh {
namespace {

// Barycentric weights of an interior split below this are taken as 0 (the point is on an edge or a corner).
constexpr double kOnEdge = 1e-9;

double cross2(Point a, Point b) { return a.real() * b.imag() - a.imag() * b.real(); }

Barycentric barycentric_of(Point q, Point a, Point b, Point c) {
  const double area = cross2(b - a, c - a);
  const double wa = cross2(b - q, c - q) / area;
  const double wb = cross2(c - q, a - q) / area;
  return {wa, wb, 1.0 - wa - wb};
}

// The corner index k of face f with f[k]–f[k+1] the edge a–b (either direction).
int index_of_edge(const Face& f, int a, int b) {
  for (int k = 0; k < 3; ++k) {
    const int p = f[k], q = f[(k + 1) % 3];
    if ((p == a && q == b) || (p == b && q == a)) return k;
  }
  return -1;
}

// The region as a mutable triangle soup with vertex → face adjacency, in local ids.
class Refiner {
 public:
  Refiner(const TriangleMesh& mesh, const MeshRegion& region, const RegionVertexData& data)
      : mesh_(mesh), region_(region), data_(data), faces_(region.local.faces), source_(region.faces) {
    pos_ = region.local.vertices;
    around_.resize(pos_.size());
    for (int f = 0; f < static_cast<int>(faces_.size()); ++f) {
      for (int v : faces_[f]) around_[v].push_back(f);
    }
  }

  int vertex_count() const { return static_cast<int>(pos_.size()); }
  const std::vector<Face>& faces() const { return faces_; }
  const std::vector<int>& source() const { return source_; }
  const std::vector<Vec3>& positions() const { return pos_; }
  const std::vector<SurfacePoint>& new_points() const { return new_points_; }
  const std::vector<int>& faces_around(int v) const { return around_[v]; }

  // The other face on edge a–b of face f, or −1 on the region's boundary.
  int neighbour(int f, int a, int b) const {
    for (int g : around_[a]) {
      if (g == f) continue;
      const Face& face = faces_[g];
      if (face[0] == b || face[1] == b || face[2] == b) return g;
    }
    return -1;
  }

  // Face f's longest edge in the frame, as (first corner index k: edge f[k]–f[k+1]), with ties broken by the
  // vertex ids so that "longest" is a strict order over edges (longest-edge paths then cannot cycle).
  int longest_edge(int f) const {
    const Face& face = faces_[f];
    int best = 0;
    for (int k = 1; k < 3; ++k) {
      if (edge_key(face[k], face[(k + 1) % 3]) > edge_key(face[best], face[(best + 1) % 3])) best = k;
    }
    return best;
  }

  double edge_length(int a, int b) const { return std::abs(data_.frame_px[b] - data_.frame_px[a]); }
  Point edge_midpoint_texture(int a, int b) const { return 0.5 * (data_.texture_px[a] + data_.texture_px[b]); }

  // Barycentric weights of a frame point in input face `face` (mesh id).
  Barycentric in_input_face(int face, Point q) const {
    const Face& f = mesh_.faces[face];
    return barycentric_of(q, data_.frame_px[region_.local_vertex[f[0]]], data_.frame_px[region_.local_vertex[f[1]]],
                          data_.frame_px[region_.local_vertex[f[2]]]);
  }

  int add_vertex(Vec3 p, Point frame, Point embedding, Point texture, SurfacePoint where) {
    pos_.push_back(p);
    data_.frame_px.push_back(frame);
    data_.embedding.push_back(embedding);
    data_.texture_px.push_back(texture);
    new_points_.push_back(where);
    around_.emplace_back();
    return vertex_count() - 1;
  }

  // The vertex at weight t from a to b on edge a–b (linear in 3D, frame and embedding); its texture position is
  // `texture`. Every face on the edge is split in two, keeping its orientation.
  int split_edge(int a, int b, double t, Point texture) {
    const auto lerp = [t](auto x, auto y) { return (1.0 - t) * x + t * y; };
    const std::vector<int> on_edge = faces_on_edge(a, b);
    const Point frame = lerp(data_.frame_px[a], data_.frame_px[b]);
    const int source = source_[on_edge.front()];
    const int m = add_vertex(lerp(pos_[a], pos_[b]), frame, lerp(data_.embedding[a], data_.embedding[b]), texture,
                             {source, in_input_face(source, frame)});
    for (int f : on_edge) {
      const Face face = faces_[f];
      int k = 0;
      while (!((face[k] == a && face[(k + 1) % 3] == b) || (face[k] == b && face[(k + 1) % 3] == a))) ++k;
      const int p = face[k], q = face[(k + 1) % 3], c = face[(k + 2) % 3];
      faces_[f] = {p, m, c};
      const int g = add_face({m, q, c}, source_[f]);
      replace(around_[q], f, g);
      around_[c].push_back(g);
      around_[m].push_back(f);
      around_[m].push_back(g);
    }
    return m;
  }

  // The vertex at barycentric weights w inside face f, which becomes three faces.
  int split_face(int f, const Barycentric& w, Point texture, SurfacePoint where) {
    const Face face = faces_[f];
    Vec3 p{0.0, 0.0, 0.0};
    Point frame(0.0, 0.0), embedding(0.0, 0.0);
    for (int k = 0; k < 3; ++k) {
      p = p + w[k] * pos_[face[k]];
      frame += w[k] * data_.frame_px[face[k]];
      embedding += w[k] * data_.embedding[face[k]];
    }
    const int m = add_vertex(p, frame, embedding, texture, where);
    const int a = face[0], b = face[1], c = face[2];
    faces_[f] = {a, b, m};
    const int g1 = add_face({b, c, m}, source_[f]);
    const int g2 = add_face({c, a, m}, source_[f]);
    around_[a].push_back(g2);
    around_[b].push_back(g1);
    replace(around_[c], f, g1);
    around_[c].push_back(g2);
    around_[m] = {f, g1, g2};
    return m;
  }

 private:
  std::tuple<double, int, int> edge_key(int a, int b) const {
    return {std::norm(data_.frame_px[b] - data_.frame_px[a]), std::min(a, b), std::max(a, b)};
  }

  std::vector<int> faces_on_edge(int a, int b) const {
    std::vector<int> out;
    for (int f : around_[a]) {
      const Face& face = faces_[f];
      if (face[0] == b || face[1] == b || face[2] == b) out.push_back(f);
    }
    if (out.empty())
      throw NumericalError("refinement: vertices " + std::to_string(a) + " and " + std::to_string(b) +
                           " share no face");
    return out;
  }

  int add_face(Face face, int source) {
    faces_.push_back(face);
    source_.push_back(source);
    return static_cast<int>(faces_.size()) - 1;
  }

  static void replace(std::vector<int>& list, int from, int to) { std::replace(list.begin(), list.end(), from, to); }

  const TriangleMesh& mesh_;
  const MeshRegion& region_;
  const RegionVertexData& data_;
  std::vector<Face> faces_;
  std::vector<int> source_;  // per local face: the input face (mesh id) it lies in
  std::vector<Vec3> pos_;
  std::vector<std::vector<int>> around_;
  std::vector<SurfacePoint> new_points_;
};

// The local vertex a feature becomes: a corner it sits on, or a vertex inserted on an edge or inside a face.
int insert_feature(Refiner& r, const MeshRegion& region, const TriangleMesh& mesh, const PlacedFeature& p,
                   const RegionVertexData& data) {
  const Barycentric& w = p.location.barycentric;
  const int corner = static_cast<int>(std::max_element(w.begin(), w.end()) - w.begin());
  if (w[corner] >= 1.0 - kOnEdge) return region.local_vertex[mesh.faces[p.location.face][corner]];
  // The current part of the input face that holds the feature's frame position best.
  const Point q = p.feature.target;
  int best = -1;
  Barycentric best_w{};
  double best_min = -1e300;
  for (int f = 0; f < static_cast<int>(r.faces().size()); ++f) {
    if (r.source()[f] != p.location.face) continue;
    const Face& face = r.faces()[f];
    const Barycentric b = barycentric_of(q, data.frame_px[face[0]], data.frame_px[face[1]], data.frame_px[face[2]]);
    const double least = std::min({b[0], b[1], b[2]});
    if (least > best_min) {
      best_min = least;
      best = f;
      best_w = b;
    }
  }
  const Face face = r.faces()[best];
  const int top = static_cast<int>(std::max_element(best_w.begin(), best_w.end()) - best_w.begin());
  if (best_w[top] >= 1.0 - kOnEdge) return face[top];
  const int low = static_cast<int>(std::min_element(best_w.begin(), best_w.end()) - best_w.begin());
  if (best_w[low] <= kOnEdge) {
    const int a = face[(low + 1) % 3], b = face[(low + 2) % 3];
    const double t = best_w[(low + 2) % 3] / (best_w[(low + 1) % 3] + best_w[(low + 2) % 3]);
    return r.split_edge(a, b, t, p.feature.source);
  }
  return r.split_face(best, best_w, p.feature.source, p.location);
}

// Rivara's longest-edge propagation path from face f: follows the neighbour across each face's longest edge until
// two faces share it as their longest (or it is on the boundary), and bisects that edge. Repeated until f itself is
// split, it keeps every triangle's smallest angle at least half the smallest angle it started from (Rivara 1984),
// so triangles shrink without degenerating. Returns false when the edge to bisect is shorter than `min_edge_px`.
bool bisect_along_longest_edges(Refiner& r, int f, double min_edge_px, bool interpolate, int& split_edges) {
  const Face start = r.faces()[f];
  while (r.faces()[f] == start) {
    int face = f;
    for (;;) {
      const int k = r.longest_edge(face);
      const int a = r.faces()[face][k], b = r.faces()[face][(k + 1) % 3];
      const int other = r.neighbour(face, a, b);
      if (other < 0 || r.longest_edge(other) == index_of_edge(r.faces()[other], a, b)) {
        if (r.edge_length(a, b) < min_edge_px) return false;
        r.split_edge(a, b, 0.5, interpolate ? r.edge_midpoint_texture(a, b) : Point(0.0, 0.0));
        ++split_edges;
        break;
      }
      face = other;
    }
  }
  return true;
}

// The faces outside the region across a boundary edge that refinement split (a feature on it, a bisection, a split
// between two pins) take the edge's new vertices too, so that no T-junction is left where the region meets the rest
// of the mesh: each new vertex, in order along the edge, splits the outside triangle that has the rest of the edge
// towards its opposite corner (points on an edge of a non-degenerate triangle leave every part non-degenerate). The
// first part keeps the outside face's id, the others are appended, each with that face as its source.
// `output_vertex`: a local vertex's output id; `nv0`: the region's vertices before refinement.
template <class OutputVertex>
void split_outside_faces(const TriangleMesh& mesh, const MeshRegion& region, const Refiner& r, int nv0,
                         const OutputVertex& output_vertex, MeshRefinement& out) {
  if (r.vertex_count() == nv0) return;
  // The refined region's boundary: each boundary vertex's next along it (a disk: one outgoing boundary edge each).
  std::unordered_set<std::uint64_t> half_edges;
  const auto key = [](int a, int b) { return (static_cast<std::uint64_t>(a) << 32U) | static_cast<std::uint32_t>(b); };
  for (const Face& f : r.faces()) {
    for (int k = 0; k < 3; ++k) half_edges.insert(key(f[k], f[(k + 1) % 3]));
  }
  std::vector<int> next(static_cast<std::size_t>(r.vertex_count()), -1);
  for (const Face& f : r.faces()) {
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      if (!half_edges.contains(key(b, a))) next[a] = b;
    }
  }
  for (int f = 0; f < mesh.face_count(); ++f) {
    if (region.local_face[f] >= 0) continue;
    std::vector<Face> parts{mesh.faces[f]};
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
      const int la = region.local_vertex[a], lb = region.local_vertex[b];
      if (la < 0 || lb < 0) continue;
      // The region runs b → a along this edge: its new vertices, then a (else the edge is not the region's).
      std::vector<int> along;
      int v = next[lb];
      while (v >= nv0 && static_cast<int>(along.size()) < r.vertex_count()) {
        along.push_back(v);
        v = next[v];
      }
      if (along.empty() || v != la) continue;
      std::reverse(along.begin(), along.end());  // from a towards b
      int from = a;                              // the part with the edge from → b is split at each new vertex
      for (const int w : along) {
        const int at = output_vertex(w);
        const auto with_edge = std::find_if(parts.begin(), parts.end(), [&](const Face& part) {
          const int j = index_of_edge(part, from, b);
          return j >= 0 && part[j] == from;
        });
        if (with_edge != parts.end()) {
          const Face part = *with_edge;
          const int x = part[(index_of_edge(part, from, b) + 2) % 3];
          *with_edge = Face{from, at, x};
          parts.push_back(Face{at, b, x});
        }
        from = at;
      }
    }
    if (parts.size() == 1) continue;
    out.mesh.faces[f] = parts[0];
    for (std::size_t i = 1; i < parts.size(); ++i) {
      out.mesh.faces.push_back(parts[i]);
      out.source_face.push_back(f);
    }
  }
}

}  // namespace

MeshRefinement refine_region(const TriangleMesh& mesh, MeshRegion& region, const RegionVertexData& data,
                             std::span<const PlacedFeature> features, const InverseMap& inverse_map,
                             const RefinementOptions& options) {
  MeshRefinement out;
  out.input_vertices = mesh.vertex_count();
  out.input_faces = mesh.face_count();
  const int nv0 = region.vertex_count();
  const int nf0 = region.face_count();
  Refiner r(mesh, region, data);

  std::vector<int> feature_vertex;
  for (const PlacedFeature& p : features) {
    const int before = r.vertex_count();
    const int v = insert_feature(r, region, mesh, p, data);
    if (r.vertex_count() > before) ++out.feature_vertices;
    data.texture_px[v] = p.feature.source;  // f⁻¹(target) = source: the warp interpolates its features
    feature_vertex.push_back(v);
  }

  const auto positive = [&](const Face& f) {
    return uv_triangle_positive(data.texture_px[f[0]], data.texture_px[f[1]], data.texture_px[f[2]],
                                options.texture_width, options.texture_height);
  };
  out.vertex_limit = options.max_vertex_factor * std::max(nv0, 64);
  if (options.max_vertices > 0) out.vertex_limit = std::max(std::min(out.vertex_limit, options.max_vertices), nv0);
  // Untangled UVs are no longer the warp's: a new vertex starts at its edge's midpoint there (it adds no flip; the
  // next untangling moves it), not at the warp's inverse.
  const bool interpolate = static_cast<bool>(options.relax);
  const auto flipped_faces = [&] {
    std::vector<int> flipped;
    for (int f = 0; f < static_cast<int>(r.faces().size()); ++f) {
      if (!positive(r.faces()[f])) flipped.push_back(f);
    }
    return flipped;
  };
  if (options.split_feature_edges) {
    // The edges first, then their splits (a split changes the faces the next edge is found in, not the edge).
    std::vector<char> is_feature(static_cast<std::size_t>(r.vertex_count()), 0);
    for (const int v : feature_vertex) is_feature[v] = 1;
    std::vector<std::pair<int, int>> edges;
    for (const Face& f : r.faces()) {
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        if (is_feature[a] && is_feature[b]) edges.emplace_back(std::min(a, b), std::max(a, b));
      }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    const int first = r.vertex_count();
    for (const auto& [a, b] : edges) {
      if (r.vertex_count() >= out.vertex_limit) {  // each split adds a vertex: the bound holds here too
        out.stop = RefinementStop::kVertexLimit;
        break;
      }
      r.split_edge(a, b, 0.5, interpolate ? r.edge_midpoint_texture(a, b) : Point(0.0, 0.0));
      ++out.split_edges;
    }
    if (!interpolate && r.vertex_count() > first) {
      const std::span<Point> added(data.texture_px.begin() + first, data.texture_px.end());
      std::copy(data.frame_px.begin() + first, data.frame_px.end(), added.begin());
      inverse_map(added);
    }
  }
  for (;;) {
    std::vector<int> flipped = flipped_faces();
    if (out.rounds == 0) out.flipped_before = static_cast<int>(flipped.size());  // the first pass: before any bisection
    if (options.relax && !flipped.empty()) {
      options.relax(TriangleMesh{r.positions(), r.faces()}, data.texture_px, feature_vertex);
      flipped = flipped_faces();
    }
    out.flipped_after = static_cast<int>(flipped.size());
    if (flipped.empty() || !options.bisect) break;
    if (r.vertex_count() >= out.vertex_limit) {
      out.stop = RefinementStop::kVertexLimit;
      break;
    }
    if (options.max_rounds > 0 && out.rounds >= options.max_rounds) {
      out.stop = RefinementStop::kRoundLimit;
      break;
    }
    const int first = r.vertex_count();
    for (const int f : flipped) {
      if (!bisect_along_longest_edges(r, f, options.min_edge_px, interpolate, out.split_edges))
        out.stop = RefinementStop::kMinEdge;
      if (r.vertex_count() >= out.vertex_limit) break;
    }
    if (r.vertex_count() == first) break;  // every flipped triangle is at the smallest meaningful size
    out.stop = RefinementStop::kFlipFree;
    ++out.rounds;
    if (interpolate) continue;
    const std::span<Point> added(data.texture_px.begin() + first, data.texture_px.end());
    std::copy(data.frame_px.begin() + first, data.frame_px.end(), added.begin());
    inverse_map(added);
  }
  if (out.flipped_after == 0) out.stop = RefinementStop::kFlipFree;

  // The output mesh: local vertex i ≥ nv0 is output vertex input_vertices + (i − nv0); local face k ≥ nf0 is
  // output face input_faces + (k − nf0).
  const auto output_vertex = [&](int local) {
    return local < nv0 ? region.vertices[local] : out.input_vertices + (local - nv0);
  };
  out.mesh.vertices = mesh.vertices;
  for (int i = nv0; i < r.vertex_count(); ++i) out.mesh.vertices.push_back(r.positions()[i]);
  out.mesh.faces = mesh.faces;
  out.source_face.resize(static_cast<std::size_t>(mesh.face_count()));
  for (int f = 0; f < mesh.face_count(); ++f) out.source_face[f] = f;
  std::vector<int> region_faces = region.faces;
  for (int k = 0; k < static_cast<int>(r.faces().size()); ++k) {
    const Face& local = r.faces()[k];
    const Face face{output_vertex(local[0]), output_vertex(local[1]), output_vertex(local[2])};
    if (k < nf0) {
      out.mesh.faces[region.faces[k]] = face;
    } else {
      out.mesh.faces.push_back(face);
      out.source_face.push_back(r.source()[k]);
      region_faces.push_back(out.mesh.face_count() - 1);
    }
  }
  out.new_vertices = r.new_points();
  split_outside_faces(mesh, region, r, nv0, output_vertex, out);

  // Feature places on the output mesh, before the local ids are renumbered by the new region.
  for (int v : feature_vertex) {
    const int k = r.faces_around(v).front();
    const int face = k < nf0 ? region.faces[k] : out.input_faces + (k - nf0);
    SurfacePoint s{face, {0.0, 0.0, 0.0}};
    for (int j = 0; j < 3; ++j) {
      if (out.mesh.faces[face][j] == output_vertex(v)) s.barycentric[j] = 1.0;
    }
    out.feature_locations.push_back(s);
  }

  MeshRegion refined = disk_region(out.mesh, std::move(region_faces), proto::InputLocation::file("refined region"));
  // The new region numbers its vertices by ascending output id: carry the per-vertex data over.
  const auto renumber = [&](std::vector<Point>& values) {
    std::vector<Point> moved(values.size());
    for (int i = 0; i < r.vertex_count(); ++i) moved[refined.local_vertex[output_vertex(i)]] = values[i];
    values = std::move(moved);
  };
  renumber(data.frame_px);
  renumber(data.embedding);
  renumber(data.texture_px);
  region = std::move(refined);
  return out;
}

}  // namespace texwarp::mesh
