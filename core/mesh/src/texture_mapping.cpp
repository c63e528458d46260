// The texture-mapping pipeline: see texture_mapping.hpp.
#include "texwarp/mesh/texture_mapping.hpp"

#include <algorithm>
#include <chrono>

#include "texwarp/core/numerical_error.hpp"
#include "texwarp/mesh/embedding_repair.hpp"
#include "texwarp/mesh/uv_orientation.hpp"
#include "texwarp/mesh/uv_untangling.hpp"

#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Bisection alternating with untangling runs when plain bisection and untangling leave flips or more than this many
// times the input's faces, and stops before it makes more: at the region's vertices plus (factor − 1)/2 × its faces
// (a split adds at most two faces per vertex; a bisection path that crosses the bound still ends), or after
// kAlternatingRounds rounds.
constexpr int kAlternatingFaceFactor = 3;
constexpr int kAlternatingRounds = 12;
// Untangling between its rounds gives up after this many rounds without fewer flips (the next bisection round gives
// it more vertices to try with). Flip-free cases of the pinned-unwrap benchmark's 72 by patience/rounds (with a bound
// of 3× the vertices): 30/8: 63 (the cases it did not save up to 13 s); 10/8: 65 (5.7 s); 10/12: 66 (9 s); 10/16: 66;
// 5/8 and 5/12: 64; 3/16: 65.
constexpr int kAlternatingPatience = 10;
// The alternating run's untangling starts 32 edges around the flips (UvUntanglingOptions::rings): its new free
// midpoints need room. With 8 the test grid's clustered pins (uv_guarantee_test) were no longer unfolded; 16 and 32
// unfold them; the pinned-unwrap benchmark's figures (docs/internals.md) were measured at 32.
constexpr int kAlternatingRings = 32;
// The optimisation holds a positional feature's faces with it only while every face they touch is at most this
// anisotropic (σ1/σ2) in the UVs it starts from (held_vertices).
constexpr double kHeldFaceMaxAspect = 16.0;

}  // namespace

int alternating_vertex_limit(int input_vertices, int input_faces, int kept_vertices, int max_vertices) {
  const int bound = input_vertices + (kAlternatingFaceFactor - 1) * input_faces / 2;
  if (max_vertices <= 0) return bound;
  // The kept refinement's new vertices are charged against the budget's new vertices.
  return std::min(bound, max_vertices - std::max(kept_vertices - input_vertices, 0));
}

namespace {

// The region's local vertices that carry feature i: its vertex, or the corners of the face it lies inside (without
// refinement), whose UVs then hold the feature's interpolated position.
std::vector<int> feature_corners(const TriangleMesh& mesh, const TextureMapping& m, std::size_t i) {
  const TriangleMesh& out_mesh = output_mesh(mesh, m.refinement);
  const MeshRegion& region = m.region;
  const SurfacePoint& s = m.refinement ? m.refinement->feature_locations[i] : m.features[i].location;
  const Face& face = out_mesh.faces[s.face];
  for (int k = 0; k < 3; ++k) {
    if (s.barycentric[k] >= 1.0 - 1e-9) return {region.local_vertex[face[k]]};
  }
  return {region.local_vertex[face[0]], region.local_vertex[face[1]], region.local_vertex[face[2]]};
}

// The region's local vertices that carry the features (feature_corners of each), ascending.
std::vector<int> feature_vertices(const TriangleMesh& mesh, const TextureMapping& m) {
  std::vector<int> out;
  for (std::size_t i = 0; i < m.features.size(); ++i) {
    const std::vector<int> corners = feature_corners(mesh, m, i);
    out.insert(out.end(), corners.begin(), corners.end());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

// Whether an edge of the region's faces joins two of feature_vertices' (a feature inside a face counts its corners):
// only then does splitting the edges between pins change anything.
bool pins_are_neighbours(const TriangleMesh& mesh, const TextureMapping& m) {
  std::vector<char> pin(static_cast<std::size_t>(m.region.vertex_count()), 0);
  for (const int v : feature_vertices(mesh, m)) pin[v] = 1;
  return std::any_of(m.region.local.faces.begin(), m.region.local.faces.end(),
                     [&](const Face& f) { return pin[f[0]] + pin[f[1]] + pin[f[2]] >= 2; });
}

// The vertices the optimisation holds: the feature vertices and the faces around them. Around a point held alone an
// isometric energy gathers the whole displacement in the one-ring (in 2D a point load's strain grows like 1/r); held
// with its faces, the warp's smooth neighbourhood stays and the optimisation spreads the rest. For a gradient feature
// those faces carry its frame. A positional feature's faces are held only while no face they touch is turned over,
// degenerate in the UVs or more anisotropic than kHeldFaceMaxAspect in `domain` (the UVs the optimisation starts from;
// a face of zero surface area counts as infinitely so): where the warp bends faster than the mesh resolves (pins one
// edge apart, moved apart), the one-ring is no smooth neighbourhood, and holding it kept its worst triangle as it was.
// A face is then held unsmooth only when its corners are features' own vertices (the pins are exact) or a gradient
// feature's faces hold them.
std::vector<int> held_vertices(const TriangleMesh& mesh, const TextureMapping& m, std::span<const Point> domain) {
  const MeshRegion& region = m.region;
  const UvMetrics start = uv_metrics(region.local, domain, true);
  std::vector<std::vector<int>> around(static_cast<std::size_t>(region.vertex_count()));
  for (int f = 0; f < region.face_count(); ++f) {
    for (int v : region.local.faces[f]) around[v].push_back(f);
  }
  const auto smooth = [&](int f) {
    const TriangleDistortion& d = start.per_triangle[static_cast<std::size_t>(f)];
    return !d.flipped && !d.degenerate && d.aspect <= kHeldFaceMaxAspect;
  };
  // A face is held when its three corners are, whichever features' faces brought them: so every face that touches a
  // vertex of a positional feature's faces must be smooth for them to be held.
  const auto smooth_around = [&](int v) { return std::all_of(around[v].begin(), around[v].end(), smooth); };
  std::vector<char> held(static_cast<std::size_t>(region.vertex_count()), 0);
  for (std::size_t i = 0; i < m.features.size(); ++i) {
    const std::vector<int> corners = feature_corners(mesh, m, i);
    bool with_faces = true;
    if (!m.features[i].feature.is_gradient()) {
      for (int v : corners) {
        for (int f : around[v]) {
          const Face& face = region.local.faces[f];
          with_faces = with_faces && std::all_of(face.begin(), face.end(), smooth_around);
        }
      }
    }
    for (int v : corners) {
      held[v] = 1;
      if (!with_faces) continue;
      for (int f : around[v]) {
        for (int w : region.local.faces[f]) held[w] = 1;
      }
    }
  }
  std::vector<int> out;
  for (int v = 0; v < region.vertex_count(); ++v) {
    if (held[v]) out.push_back(v);
  }
  return out;
}

// The check UVs handed out must pass: positive as written in the texture's pixels (domain positions, v up, are
// pixels with y negated).
UvTriangleCheck positive_as_written(const TextureMappingOptions& options) {
  const int w = options.texture_width, h = options.texture_height;
  return [w, h](Point a, Point b, Point c) {
    return uv_triangle_positive(std::conj(a), std::conj(b), std::conj(c), w, h);
  };
}

// Untangles texture positions (pixels of the original texture, per vertex of `local`) with `held` fixed
// (uv_untangling.hpp); they are replaced only by a result with fewer flips as written.
UvUntangling untangle_texture_px(const TriangleMesh& local, std::span<Point> texture_px, std::span<const int> held,
                                 const TextureMappingOptions& options, const UvUntanglingOptions& untangling,
                                 const RunControl& control) {
  std::vector<Point> domain = pixels_to_domain(texture_px);
  const UvUntangling out = untangle_uvs(local, domain, held, positive_as_written(options), untangling, control);
  if (out.applied) {
    for (std::size_t i = 0; i < domain.size(); ++i) texture_px[i] = std::conj(domain[i]);
  }
  return out;
}

// Untangles the mapping's UVs into the original texture, the features' vertices held; nothing when no triangle flips.
std::optional<UvUntanglingStage> untangle_mapping(const TriangleMesh& mesh, TextureMapping& m,
                                                  const TextureMappingOptions& options, const RunControl& control) {
  const auto start = std::chrono::steady_clock::now();
  UvUntanglingStage stage;
  stage.result = untangle_texture_px(m.region.local, m.texture_px, feature_vertices(mesh, m), options, {}, control);
  if (stage.result.rejected_before == 0) return std::nullopt;
  stage.seconds = seconds_since(start);
  return stage;
}

// What refinement and untangling change in a mapping: a snapshot to go back to.
struct MappingState {
  MeshRegion region;
  std::vector<Point> frame_px, embedding, texture_px;
  std::optional<MeshRefinement> refinement;
  std::optional<RefinementCounts> refinement_counts;
  std::optional<UvUntanglingStage> untangling;

  static MappingState of(const TextureMapping& m) {
    return {m.region, m.frame.pixels, m.lscm.positions, m.texture_px, m.refinement, m.refinement_counts, m.untangling};
  }
  // UV triangles not positive as written, when taken after untangling.
  int flipped() const { return untangling ? untangling->result.rejected_after : 0; }
  void restore(TextureMapping& m) const {
    m.region = region;
    m.frame.pixels = frame_px;
    m.lscm.positions = embedding;
    m.texture_px = texture_px;
    m.refinement = refinement;
    m.refinement_counts = refinement_counts;
    m.untangling = untangling;
  }
};

// `optimize: stretch` on the mapping's UVs into the original texture. Where triangles still flip (refinement and
// untangling left them), the others are optimised with the flipped ones' corners held: those stay exactly as they
// were (no flip more, none fewer), and the rest does not keep the warp's distortion for their sake.
UvOptimizationStage optimize_texture_uvs(const TriangleMesh& mesh, TextureMapping& m,
                                         const TextureMappingOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  UvOptimizationStage stage;
  std::vector<Point> domain = pixels_to_domain(m.texture_px);
  stage.before = uv_metrics(m.region.local, domain);
  const UvTriangleCheck positive = positive_as_written(options);
  const TriangleMesh& local = m.region.local;
  TriangleMesh unflipped;  // the region's triangles that are positive as written, when some are not
  std::vector<char> corner_of_flip(domain.size(), 0);
  for (const Face& f : local.faces) {
    if (positive(domain[f[0]], domain[f[1]], domain[f[2]])) continue;
    for (const int v : f) corner_of_flip[v] = 1;
  }
  const bool flips = std::find(corner_of_flip.begin(), corner_of_flip.end(), 1) != corner_of_flip.end();
  if (flips) {
    unflipped.vertices = local.vertices;
    for (const Face& f : local.faces) {
      if (positive(domain[f[0]], domain[f[1]], domain[f[2]])) unflipped.faces.push_back(f);
    }
  }
  // Untangled UVs are no longer the warp's around the pins: only the features' vertices are held then, and their
  // worst triangles (near-degenerate where a fold was undone) are what the optimisation must improve most, so they
  // are no bound: with the bound, no step was taken on the benchmark's untangled cases.
  const bool untangled = m.untangling && m.untangling->result.applied;
  stage.fixed = untangled ? feature_vertices(mesh, m) : held_vertices(mesh, m, domain);
  for (std::size_t v = 0; v < corner_of_flip.size(); ++v) {
    if (corner_of_flip[v]) stage.fixed.push_back(static_cast<int>(v));
  }
  std::sort(stage.fixed.begin(), stage.fixed.end());
  stage.fixed.erase(std::unique(stage.fixed.begin(), stage.fixed.end()), stage.fixed.end());
  UvOptimizationOptions optimization;
  optimization.limit_worst = !untangled;
  if (untangled) optimization.max_iterations = 100;
  stage.result = optimize_uvs(flips ? unflipped : local, domain, stage.fixed, positive, optimization);
  stage.applied = true;
  for (std::size_t i = 0; i < domain.size(); ++i) m.texture_px[i] = std::conj(domain[i]);
  stage.seconds = seconds_since(start);
  return stage;
}

// The warp's inverse map of the region's vertices, then refinement and untangling as `options` ask (map_texture).
void warp_and_refine(WarpBackend& backend, const TriangleMesh& mesh, TextureMapping& out,
                     const TextureMappingOptions& options, const RunControl& control) {
  auto start = std::chrono::steady_clock::now();

  out.texture_px = out.frame.pixels;
  map_points(backend, *out.problem, out.texture_px, Direction::kInverse, control);
  // A feature on a vertex: f⁻¹(target) = source exactly (the warp interpolates its features), not within the
  // integration's tolerance.
  for (const PlacedFeature& p : out.features) {
    const Barycentric& w = p.location.barycentric;
    for (int k = 0; k < 3; ++k) {
      if (w[k] >= 1.0 - 1e-9)
        out.texture_px[out.region.local_vertex[mesh.faces[p.location.face][k]]] = p.feature.source;
    }
  }
  out.warp_seconds = seconds_since(start);
  // With `optimize: stretch`, UVs that still flip are untangled (uv_untangling.hpp) before any face is added:
  // bisection, which adds faces, runs only when untangling on the input's faces (features made vertices) leaves flips,
  // and its result is untangled in turn; of the two, the one with fewer flips is kept (the first when equal). When
  // flips or more than 3× the faces remain, bisection alternating with untangling is tried as well.
  const bool untangle = options.optimize == proto::UvOptimize::kStretch;
  if (options.refine) {
    start = std::chrono::steady_clock::now();
    RefinementOptions refinement;
    refinement.texture_width = options.texture_width;
    refinement.texture_height = options.texture_height;
    refinement.min_edge_px = 16.0 * out.problem->options().tolerance_px;
    refinement.max_vertices = options.max_refined_vertices;
    const MappingState input = MappingState::of(out);
    const InverseMap inverse = [&](std::span<Point> points) {
      map_points(backend, *out.problem, points, Direction::kInverse, control);
    };
    const RegionVertexData data{out.frame.pixels, out.lscm.positions, out.texture_px};
    // A refinement made from the input stays: its counts, and the refined mesh when it changed faces (`region` refers
    // to it); else the input's region, whose faces and vertex order are the same (the input's ids stay).
    const auto keep_refinement = [&](MeshRefinement made) {
      out.refinement_counts = made;
      if (made.changed_faces()) {
        out.refinement = std::move(made);
      } else {
        out.region = input.region;
      }
    };
    // Features made vertices, no bisection.
    const auto features_only = [&](std::optional<MeshRefinement> bisected) {
      input.restore(out);
      RefinementOptions no_split = refinement;
      no_split.bisect = false;
      MeshRefinement made = refine_region(mesh, out.region, data, out.features, inverse, no_split);
      if (bisected) {
        made.stop = bisected->stop;
        made.flipped_before = bisected->flipped_before;
        made.kept = false;
      }
      keep_refinement(std::move(made));
    };
    const auto untangle_here = [&] { out.untangling = untangle_mapping(mesh, out, options, control); };
    // When bisection and untangling leave flips, or more than kAlternatingFaceFactor × the input's faces: bisection
    // alternating with untangling, from the input again. Each round splits only the triangles untangling leaves
    // flipped, the new vertices at their edge's midpoint UV, and untangling then has them to unfold with (a triangle
    // whose corners are all pins cannot be unfolded on its own faces, but its edges' midpoints are free). Bounded by
    // the region's vertices plus (kAlternatingFaceFactor − 1)/2 × its faces and by kAlternatingRounds rounds; it stays
    // when it flips less, or as little on fewer faces. `split_pin_edges`: every edge between two pins split first.
    const auto alternate = [&](bool split_pin_edges) {
      const int input_faces = input.region.face_count();
      const MappingState best = MappingState::of(out);
      input.restore(out);
      RefinementOptions alternating_refinement = refinement;
      alternating_refinement.max_vertex_factor = kAlternatingFaceFactor;
      alternating_refinement.max_vertices = alternating_vertex_limit(
          input.region.vertex_count(), input_faces, best.region.vertex_count(), refinement.max_vertices);
      if (alternating_refinement.max_vertices <= input.region.vertex_count()) {
        best.restore(out);  // the budget holds no second refinement beside the first
        return;
      }
      alternating_refinement.max_rounds = kAlternatingRounds;
      alternating_refinement.split_feature_edges = split_pin_edges;
      std::optional<UvUntanglingStage> stage;
      UvUntanglingOptions alternating;
      alternating.patience = kAlternatingPatience;
      alternating.rings = kAlternatingRings;
      alternating_refinement.relax = [&](const TriangleMesh& local, std::span<Point> texture_px,
                                         std::span<const int> held) {
        const auto begin = std::chrono::steady_clock::now();
        const UvUntangling u = untangle_texture_px(local, texture_px, held, options, alternating, control);
        if (!stage) {
          stage.emplace();
          stage->result.rejected_before = u.rejected_before;
        }
        stage->result.rejected_after = u.rejected_after;
        stage->result.rounds += u.rounds;
        stage->result.applied = stage->result.applied || u.applied;
        stage->seconds += seconds_since(begin);
      };
      std::optional<MeshRefinement> refined;
      try {
        refined = refine_region(mesh, out.region, data, out.features, inverse, alternating_refinement);
      } catch (const NumericalError&) {
        // A further try only: what the first found stands.
        best.restore(out);
        return;
      }
      const int faces = out.region.face_count();
      if (refined->flipped_after > best.flipped() ||
          (refined->flipped_after == best.flipped() && faces >= best.region.face_count())) {
        best.restore(out);
        return;
      }
      keep_refinement(std::move(*refined));
      out.untangling = stage;
    };
    // Tried as it is, then, where flips remain and two pins are neighbours, with the edges between pins split first
    // (without such an edge the second run would be the first again): which of the two unfolds
    // clustered pins depends on the case (the pinned-unwrap benchmark's cluster cases: each saves two the other
    // does not).
    bool neighbouring_pins = false;  // an edge joins two pins (set below, before anything is bisected)
    const auto alternate_when_needed = [&] {
      const auto needed = [&] {
        const int flips = out.untangling ? out.untangling->result.rejected_after : 0;  // as MappingState::flipped()
        return flips > 0 || out.region.face_count() > kAlternatingFaceFactor * input.region.face_count();
      };
      if (needed()) alternate(false);
      if (out.untangling && out.untangling->result.rejected_after > 0 && neighbouring_pins) alternate(true);
    };
    std::optional<MappingState> untangled_first;  // when untangling on the input's faces left flips
    if (untangle) {
      features_only(std::nullopt);
      // Seen on the features-only faces, the start of the split run (not on what bisection later makes of them).
      neighbouring_pins = pins_are_neighbours(mesh, out);
      untangle_here();
      if (out.untangling && out.untangling->result.rejected_after > 0) {
        untangled_first = MappingState::of(out);
        input.restore(out);
      } else if (out.untangling) {
        out.refinement_counts->stop = RefinementStop::kUntangled;
      }
    }
    if (!untangle || untangled_first) {
      // The untangled input faces back, with why bisection stopped and that it was not kept.
      const auto back_to_untangled_first = [&](RefinementStop stop) {
        untangled_first->restore(out);
        out.refinement_counts->stop = stop;
        out.refinement_counts->kept = false;
      };
      // Bisection that stops early (vertex bound, smallest edge) with more flipped triangles than it started from is
      // dropped (features still made vertices), so refining never makes flips more numerous; with untangling, the
      // untangled input faces are then what stays.
      MeshRefinement refined = refine_region(mesh, out.region, data, out.features, inverse, refinement);
      if (refined.flipped_after > 0 && refined.flipped_after >= refined.flipped_before) {
        if (untangled_first) {
          back_to_untangled_first(refined.stop);
        } else {
          features_only(std::move(refined));
        }
      } else {
        keep_refinement(std::move(refined));
        if (untangle) {
          // The bisected faces, untangled in turn where they still flip; the untangled input faces stay when they
          // flip no more.
          untangle_here();
          const int flipped = out.untangling ? out.untangling->result.rejected_after : 0;
          if (untangled_first->flipped() <= flipped) back_to_untangled_first(out.refinement_counts->stop);
        }
      }
      if (untangle) alternate_when_needed();
    }
    // Untangling runs that were not kept count as refinement's.
    out.refinement_seconds = seconds_since(start) - (out.untangling ? out.untangling->seconds : 0.0);
  } else if (untangle) {
    out.untangling = untangle_mapping(mesh, out, options, control);
  }
}

}  // namespace

std::vector<Point> pixels_to_domain(std::span<const Point> pixels) {
  std::vector<Point> out(pixels.size());
  for (std::size_t i = 0; i < pixels.size(); ++i) out[i] = Point(pixels[i].real(), -pixels[i].imag());
  return out;
}

TextureMapping map_texture(WarpBackend& backend, const TriangleMesh& mesh, MeshRegion region,
                           const SurfaceFeatureSet& features, const TextureMappingOptions& options,
                           const RunControl& control, const JsonPath& features_path) {
  if (options.texture_width <= 0 || options.texture_height <= 0) {
    throw InputError({}, "the texture must have a positive size, got " + std::to_string(options.texture_width) + "×" +
                             std::to_string(options.texture_height));
  }
  TextureMapping out;
  out.region = std::move(region);
  out.frame_width = options.frame_width > 0 ? options.frame_width : options.texture_width;
  out.frame_height = options.frame_height > 0 ? options.frame_height : options.texture_height;

  auto start = std::chrono::steady_clock::now();
  out.lscm = lscm_embedding(out.region.local, out.region.boundary);
  EmbeddingRepair repair = repair_embedding(out.region.local, out.region.boundary, std::move(out.lscm.positions));
  out.lscm.positions = std::move(repair.positions);
  out.embedding = repair.method;
  for (int f : repair.flipped_faces) out.lscm_flipped_faces.push_back(out.region.faces[f]);
  if (out.embedding != proto::EmbeddingMethod::kLscm)
    out.lscm.energy = lscm_energy(out.region.local, out.lscm.positions);
  out.lscm_seconds = seconds_since(start);

  FramePlacementOptions placement;
  placement.width = out.frame_width;
  placement.height = out.frame_height;
  placement.margin_px = options.margin_px;
  placement.rotate_to_fit = options.rotate_to_fit;
  out.frame = place_in_frame(out.lscm.positions, placement);

  out.features = place_surface_features(mesh, out.region, out.frame.pixels, features, features_path);
  // A pin is a place on the texture: outside it the UVs would point past the image.
  for (std::size_t i = 0; i < out.features.size(); ++i) {
    const Point s = out.features[i].feature.source;
    if (!(s.real() >= 0.0 && s.real() <= options.texture_width && s.imag() >= 0.0 &&
          s.imag() <= options.texture_height)) {
      const std::string id = out.features[i].feature.id;
      throw InputError(features_path.key("features").index(i).key("source"),
                       "feature " + (id.empty() ? std::to_string(i) : "\"" + id + "\"") + " at (" +
                           std::to_string(s.real()) + ", " + std::to_string(s.imag()) + ") px lies outside the " +
                           std::to_string(options.texture_width) + "×" + std::to_string(options.texture_height) +
                           " texture");
    }
  }
  std::vector<Feature> warp_features;
  warp_features.reserve(out.features.size());
  for (const PlacedFeature& p : out.features) warp_features.push_back(p.feature);
  // Trajectories that lower the pair energy (trajectory_planner.hpp; here straight ones whose pairs pass close too)
  // twist less, but where the UVs still flip with them, the planner's trajectories as found are tried too and the
  // fewer flips stay (the first when equal). The mapping before the warp is kept for that only when the plan was
  // lowered. What the choice costs beyond the kept try's own stages (counting flips, the second plan, the try not
  // kept) counts as the warp's time, as does planning the first try's trajectories; progress holds where the first
  // try left it (its consumers never go back).
  const auto plan_start = std::chrono::steady_clock::now();
  WarpOptions warp_options = features.options;
  warp_options.widen_near_misses = true;
  out.problem.emplace(warp_features, warp_options);
  std::optional<TextureMapping> placed;
  if (out.problem->trajectory_plan().energy_lowered()) {
    placed = out;
    placed->problem.reset();
  }
  const double planned = seconds_since(plan_start);
  warp_and_refine(backend, mesh, out, options, control);
  out.warp_seconds += planned;
  if (placed) {
    const auto choice_start = std::chrono::steady_clock::now();
    const std::size_t flips = evaluate_mapping(mesh, out, out.texture_px, options, false).flips.size();
    const auto spent = [](const TextureMapping& m) {
      return m.warp_seconds + m.refinement_seconds + (m.untangling ? m.untangling->seconds : 0.0);
    };
    const double first = spent(out);
    bool second_kept = false;
    if (flips > 0) {
      TextureMapping& second = *placed;
      warp_options.lower_energy = false;
      second.problem.emplace(std::move(warp_features), warp_options);
      warp_and_refine(backend, mesh, second, options, control);
      if (evaluate_mapping(mesh, second, second.texture_px, options, false).flips.size() < flips) {
        second.warp_seconds += first + seconds_since(choice_start) - spent(second);
        out = std::move(second);
        second_kept = true;
      }
    }
    if (!second_kept) out.warp_seconds += seconds_since(choice_start);
  }
  if (options.optimize == proto::UvOptimize::kStretch) out.optimization = optimize_texture_uvs(mesh, out, options);
  return out;
}

MappingQuality evaluate_mapping(const TriangleMesh& mesh, const TextureMapping& mapping,
                                std::span<const Point> texture_px, const TextureMappingOptions& options,
                                bool per_triangle) {
  MappingQuality q;
  q.texture = uv_metrics(mapping.region.local, pixels_to_domain(texture_px), true);
  q.frame = uv_metrics(mapping.region.local, pixels_to_domain(mapping.frame.pixels), true);
  for (int f = 0; f < mapping.region.face_count(); ++f) {
    if (!q.texture.per_triangle[f].flipped) continue;
    const bool embedding = q.frame.per_triangle[f].flipped || q.frame.per_triangle[f].degenerate;
    q.flips.push_back({mapping.region.faces[f], embedding ? proto::FlipCause::kEmbedding : proto::FlipCause::kWarp});
  }
  if (!per_triangle) {
    q.texture.per_triangle.clear();
    q.frame.per_triangle.clear();
  }
  const TriangleMesh& out_mesh = output_mesh(mesh, mapping.refinement);
  double sum = 0.0;
  for (std::size_t i = 0; i < mapping.features.size(); ++i) {
    const PlacedFeature& p = mapping.features[i];
    const SurfacePoint& s = mapping.refinement ? mapping.refinement->feature_locations[i] : p.location;
    const Face& f = out_mesh.faces[s.face];
    Point at(0.0, 0.0);
    for (int k = 0; k < 3; ++k) at += s.barycentric[k] * texture_px[mapping.region.local_vertex[f[k]]];
    const double r = std::abs(at - p.feature.source);
    q.residual_px.push_back(r);
    q.max_residual_px = std::max(q.max_residual_px, r);
    sum += r;
  }
  if (!q.residual_px.empty()) q.mean_residual_px = sum / static_cast<double>(q.residual_px.size());
  for (Point p : texture_px) {
    if (p.real() < 0.0 || p.imag() < 0.0 || p.real() > options.texture_width || p.imag() > options.texture_height) {
      ++q.vertices_outside_texture;
    }
  }
  return q;
}

}  // namespace texwarp::mesh
