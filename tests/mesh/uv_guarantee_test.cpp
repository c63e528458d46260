// The guarantee on what users get: refined or untangled UVs have no flipped triangle as written (float32 rounding
// included) and every pin exact, for pin sets whose moves cross; the stretch optimisation keeps both and lowers the
// distortion;
// SLIM reaches the known optimum of a sheared plane; the orientation margin holds against every rounding.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "gltf_test_files.hpp"
#include "mesh_test_shapes.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/numerical_error.hpp"
#include "texwarp/mesh/gltf_mesh.hpp"
#include "texwarp/mesh/gltf_output.hpp"
#include "texwarp/mesh/mapping_report.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/texture_mapping.hpp"
#include "texwarp/mesh/uv_convention.hpp"
#include "texwarp/mesh/uv_optimization.hpp"
#include "texwarp/mesh/uv_orientation.hpp"

namespace texwarp::mesh {
namespace {

constexpr int kTexture = 512;

// Counter-clockwise (front, v up) after each UV is rounded to float32 as glTF and Blender store it, for both UV
// origins; computed here from the rounded floats, independently of uv_orientation.hpp.
bool positive_as_float32(Point a, Point b, Point c, int width, int height) {
  for (const UvOrigin origin : {UvOrigin::kBottomLeft, UvOrigin::kTopLeft}) {
    std::array<std::array<double, 2>, 3> uv{};
    const std::array<Point, 3> px = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const auto exact = pixel_to_uv(px[k], width, height, origin);
      uv[k] = {static_cast<float>(exact[0]), static_cast<float>(exact[1])};
    }
    const double cross = (uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1]) - (uv[1][1] - uv[0][1]) * (uv[2][0] - uv[0][0]);
    // top_left has v down: the front is clockwise there.
    if (origin == UvOrigin::kBottomLeft ? !(cross > 0.0) : !(cross < 0.0)) return false;
  }
  return true;
}

int flipped_as_written(const TextureMapping& m) {
  int n = 0;
  for (const Face& f : m.region.local.faces) {
    n += positive_as_float32(m.texture_px[f[0]], m.texture_px[f[1]], m.texture_px[f[2]], kTexture, kTexture) ? 0 : 1;
  }
  return n;
}

// How a test's pins are chosen and moved.
enum class Pins {
  kRandom,    // anywhere, each moved on its own
  kCrossing,  // in pairs whose moves swap the pair's positions (paths cross)
  kCluster,   // the 12 vertices nearest one, moved together by up to ±amplitude and each by up to ±amplitude/4 more
};

// A bent 30×30 grid (1 800 faces) with 12 vertex pins moved by up to ±amplitude px (±1.25 amplitude when clustered)
// from the identity mapping's texture positions, chosen as `pins` says.
struct PinnedGrid {
  TriangleMesh mesh = testing::cylinder_strip(1.0, 2.0, 2.0, 30, 30);
  MeshRegion region = whole_mesh_region(mesh, proto::InputLocation::file("grid"));
  TextureMappingOptions options;
  SurfaceFeatureSet features;
  CpuBackend backend;

  PinnedGrid(std::uint32_t seed, double amplitude, Pins pins) {
    const bool cross = pins == Pins::kCrossing;
    options.texture_width = kTexture;
    options.texture_height = kTexture;
    const TextureMapping identity = map_texture(backend, mesh, region, {}, options);
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> pick(0, mesh.vertex_count() - 1);
    std::uniform_real_distribution<double> offset(-amplitude, amplitude);
    std::vector<int> used;
    const auto unused = [&](int v) { return std::find(used.begin(), used.end(), v) == used.end(); };
    Point shift(0.0, 0.0);
    if (pins == Pins::kCluster) {
      // The 12 vertices nearest an interior one on the grid (vertex i + 31 j is column i, row j; ties go to the lower
      // id, so the choice is exact), all moved by one shift plus their own jitter.
      const int centre = 15 * 31 + 10 + static_cast<int>(seed % 10);
      const auto key = [centre](int v) {
        const int di = v % 31 - centre % 31, dj = v / 31 - centre / 31;
        return std::pair(di * di + dj * dj, v);
      };
      std::vector<int> order(static_cast<std::size_t>(mesh.vertex_count()));
      for (int v = 0; v < mesh.vertex_count(); ++v) order[v] = v;
      std::partial_sort(order.begin(), order.begin() + 12, order.end(), [&](int a, int b) { return key(a) < key(b); });
      used.assign(order.begin(), order.begin() + 12);
      shift = Point(offset(rng), offset(rng));
    }
    while (used.size() < 12) {
      const int v = pick(rng);
      if (!unused(v)) continue;
      if (!cross) {
        used.push_back(v);
        continue;
      }
      // A partner within 1.5 × amplitude (frame pixels) whose move swaps places with v's.
      const Point here = identity.frame.pixels[region.local_vertex[v]];
      int partner = -1;
      for (int w = 0; w < mesh.vertex_count() && partner < 0; ++w) {
        const double d = std::abs(identity.frame.pixels[region.local_vertex[w]] - here);
        if (w != v && unused(w) && d > 0.5 * amplitude && d < 1.5 * amplitude) partner = w;
      }
      if (partner < 0) continue;
      used.push_back(v);
      used.push_back(partner);
    }
    for (std::size_t k = 0; k < used.size(); ++k) {
      SurfaceFeature f;
      f.id = "pin" + std::to_string(k);
      f.target = VertexTarget{used[k]};
      const Point here = identity.frame.pixels[region.local_vertex[used[k]]];
      if (cross) {
        // Past the partner's place: the two moves cross.
        const Point partner = identity.frame.pixels[region.local_vertex[used[k ^ 1]]];
        f.source = here + 1.2 * (partner - here) + 0.2 * Point(offset(rng), offset(rng));
      } else if (pins == Pins::kCluster) {
        f.source = here + shift + 0.25 * Point(offset(rng), offset(rng));
      } else {
        f.source = here + Point(offset(rng), offset(rng));
      }
      f.source =
          Point(std::clamp(f.source.real(), 1.0, kTexture - 1.0), std::clamp(f.source.imag(), 1.0, kTexture - 1.0));
      features.features.push_back(f);
    }
  }
};

// The region vertex (local id) pin i is on: a corner of its face at barycentric weight exactly 1.
int pin_vertex(const TriangleMesh& mesh, const TextureMapping& m, std::size_t i) {
  const SurfacePoint& s = m.refinement ? m.refinement->feature_locations[i] : m.features[i].location;
  int corner = 0;
  while (corner < 2 && s.barycentric[corner] != 1.0) ++corner;
  return m.region.local_vertex[output_mesh(mesh, m.refinement).faces[s.face][corner]];
}

struct Case {
  std::uint32_t seed;
  double amplitude;
  Pins pins;
  bool lower_energy = true;  // false: the planner's trajectories as found (WarpOptions::lower_energy)
};

// Refinement, then the stretch optimisation, on one pin set; the invariants that hold whatever the outcome.
struct Outcome {
  int flips_before = 0;  // as written, without refinement
  int flips_after = 0;   // as written, what the user gets
  bool flip_free = false;
  bool untangled = false;  // flip-free on the input's faces by untangling
  TextureMapping mapping;  // what the user gets
  int input_vertices = 0, input_faces = 0;
};

Outcome refine_and_check(const Case& c, proto::UvOptimize optimize = proto::UvOptimize::kStretch) {
  PinnedGrid g(c.seed, c.amplitude, c.pins);
  g.features.options.lower_energy = c.lower_energy;
  Outcome o;
  o.flips_before = flipped_as_written(map_texture(g.backend, g.mesh, g.region, g.features, g.options));
  g.options.refine = true;
  g.options.optimize = optimize;
  const TextureMapping m = map_texture(g.backend, g.mesh, g.region, g.features, g.options);
  o.mapping = m;
  o.input_vertices = g.region.vertex_count();
  o.input_faces = g.region.face_count();
  o.flips_after = flipped_as_written(m);
  const std::string where = "seed " + std::to_string(c.seed);
  EXPECT_TRUE(m.refinement_counts.has_value()) << where;
  if (!m.refinement_counts) return o;
  const RefinementCounts& counts = *m.refinement_counts;
  EXPECT_EQ(counts.flipped_before, o.flips_before) << where;
  // Never more flips than without refinement; none when it says it is flip-free.
  EXPECT_LE(o.flips_after, o.flips_before) << where;
  o.flip_free = o.flips_after == 0;
  o.untangled = counts.stop == proto::RefinementStop::kUntangled;
  if (counts.stop == proto::RefinementStop::kFlipFree || o.untangled) {
    EXPECT_EQ(o.flips_after, 0) << where;
  }
  // Untangled on the input's faces: no face added, and the report says what untangling did.
  if (o.untangled) {
    EXPECT_EQ(counts.split_edges, 0) << where;
    EXPECT_EQ(m.region.face_count(), g.region.face_count()) << where;
    EXPECT_TRUE(m.untangling && m.untangling->result.applied) << where;
  }
  if (optimize == proto::UvOptimize::kNone) {
    EXPECT_FALSE(m.untangling.has_value()) << where;
    EXPECT_FALSE(m.optimization.has_value()) << where;
    return o;
  }
  if (!counts.kept) {
    EXPECT_NE(counts.stop, proto::RefinementStop::kFlipFree) << where;
  }
  EXPECT_LE(m.region.vertex_count(), counts.vertex_limit) << where;
  // Pins exact: the vertex each pin is on holds its source, bit for bit.
  for (std::size_t i = 0; i < m.features.size(); ++i) {
    EXPECT_EQ(m.texture_px[pin_vertex(g.mesh, m, i)], m.features[i].feature.source) << where;
  }
  // The optimisation lowers the stretch (Sander's L², measured independently of the energy it minimises) and adds
  // no flip; where faces still flip it works around them, their corners held, and leaves as many flipped.
  EXPECT_TRUE(m.optimization.has_value()) << where;
  if (!m.optimization) return o;
  EXPECT_TRUE(m.optimization->applied) << where << ": " << m.optimization->skipped;
  if (m.optimization->applied) {
    const MappingQuality q = evaluate_mapping(g.mesh, m, m.texture_px, g.options);
    EXPECT_EQ(q.texture.flipped, o.flips_after) << where;
    EXPECT_LE(m.optimization->result.energy_after, m.optimization->result.energy_before) << where;
    if (o.flips_after == 0) {
      EXPECT_LT(m.optimization->result.energy_after, m.optimization->result.energy_before) << where;
      EXPECT_LT(q.texture.l2_stretch, m.optimization->before.l2_stretch) << where;
    }
    // No triangle more anisotropic than the start's worst or the default limit (untangled UVs: no such bound).
    if (!m.untangling || !m.untangling->result.applied) {
      EXPECT_LE(q.texture.max_aspect,
                std::max(m.optimization->before.max_aspect, UvOptimizationOptions{}.max_aspect) * (1.0 + 1e-9))
          << where;
    }
    EXPECT_LT(q.max_residual_px, 1e-9) << where;
  }
  return o;
}

TEST(UvGuarantee, RefinedUvsHaveNoFlipAsWrittenAndEveryPinExact) {
  int flip_free = 0, flipping_before = 0, untangled = 0;
  for (const Case c : {Case{47, 40.0, Pins::kRandom}, Case{5, 77.0, Pins::kRandom}, Case{11, 128.0, Pins::kRandom},
                       Case{3, 40.0, Pins::kCrossing}}) {
    const Outcome o = refine_and_check(c);
    flip_free += o.flip_free ? 1 : 0;
    flipping_before += o.flips_before > 0 ? 1 : 0;
    untangled += o.untangled ? 1 : 0;
  }
  EXPECT_EQ(flip_free, 4);
  EXPECT_GE(flipping_before, 2);  // the cases test something
  EXPECT_GE(untangled, 1);        // and untangling on the input's faces
}

// Crossing moves whose straight paths pass within a pixel of each other: the warp stretches 100× there. The warp's
// own UVs (optimize: none) along those straight lines: bisection reaches its vertex bound, and the refinement is
// dropped rather than leave more flips than it found. With optimize: stretch, untangling unfolds all 276 flips on the
// input's faces. With the pair energy lowered (the default), the passes widen and the warp's own bisection finishes.
TEST(UvGuarantee, RefinementThatCannotFinishNeverLeavesMoreFlips) {
  const Case straight{8, 77.0, Pins::kCrossing, false};
  const Outcome warp = refine_and_check(straight, proto::UvOptimize::kNone);
  EXPECT_GT(warp.flips_before, 0);
  EXPECT_FALSE(warp.flip_free);
  EXPECT_EQ(warp.flips_after, warp.flips_before);
  const Outcome lowered = refine_and_check(Case{8, 77.0, Pins::kCrossing}, proto::UvOptimize::kNone);
  EXPECT_TRUE(lowered.mapping.problem->trajectory_plan().energy_lowered());
  EXPECT_GT(lowered.flips_before, 0);
  EXPECT_TRUE(lowered.flip_free);
  const Outcome untangled = refine_and_check(straight);
  EXPECT_EQ(untangled.flips_before, warp.flips_before);
  EXPECT_TRUE(untangled.flip_free);
  EXPECT_TRUE(untangled.untangled);
}

// Twelve neighbouring pins moved together by up to ±128 px and each by up to ±32 px more: triangles whose three
// corners are pins come out turned over, which no map of the input's faces unfolds, and the warp's own bisection
// stops at its bound with every flip left. Bisection alternating with untangling splits those triangles' edges and
// unfolds them with the new vertices, within its vertex bound (the region's vertices plus its faces: at most 3× the
// faces).
TEST(UvGuarantee, PinsClusteredOnNeighbouringVerticesUnfoldByBisectionAlternatingWithUntangling) {
  const Case cluster{3, 128.0, Pins::kCluster};
  const Outcome warp = refine_and_check(cluster, proto::UvOptimize::kNone);
  ASSERT_GT(warp.flips_before, 0);
  EXPECT_EQ(warp.flips_after, warp.flips_before);
  ASSERT_TRUE(warp.mapping.refinement_counts);
  EXPECT_FALSE(warp.mapping.refinement_counts->kept);
  EXPECT_NE(warp.mapping.refinement_counts->stop, proto::RefinementStop::kFlipFree);

  const Outcome alternating = refine_and_check(cluster);
  EXPECT_TRUE(alternating.flip_free);
  EXPECT_FALSE(alternating.untangled);
  const TextureMapping& m = alternating.mapping;
  ASSERT_TRUE(m.refinement_counts && m.untangling);
  // The alternating run's bound: it is the refinement that stayed.
  EXPECT_EQ(m.refinement_counts->vertex_limit, alternating.input_vertices + alternating.input_faces);
  EXPECT_EQ(m.refinement_counts->stop, proto::RefinementStop::kFlipFree);
  EXPECT_GT(m.refinement_counts->split_edges, 0);
  EXPECT_LE(m.refinement_counts->rounds, 12);
  EXPECT_LE(m.region.face_count(), 3 * alternating.input_faces);
  EXPECT_EQ(m.untangling->result.rejected_before, warp.flips_before);
  EXPECT_EQ(m.untangling->result.rejected_after, 0);
  EXPECT_TRUE(m.untangling->result.applied);

  // The same refinement written into the grid as a .glb: read back as a viewer reads it (indices, float32 TEXCOORD_0
  // with glTF's top-left origin), every region triangle is front-facing, i.e. clockwise with v down.
  const TriangleMesh grid = PinnedGrid(cluster.seed, cluster.amplitude, cluster.pins).mesh;
  const proto::InputLocation file = proto::InputLocation::file("grid.glb");
  const GltfMesh gltf = parse_gltf_mesh(testing::glb_bytes(testing::gltf_parts(grid)), true, {}, file);
  ASSERT_EQ(gltf.mesh.faces, grid.faces);  // the glTF's vertex ids are the grid's
  std::vector<std::array<double, 2>> uvs;
  for (const Point px : m.texture_px) uvs.push_back(pixel_to_uv(px, kTexture, kTexture, UvOrigin::kTopLeft));
  const GltfMesh back =
      parse_gltf_mesh(textured_gltf_bytes(gltf, m.region, uvs, std::nullopt, &*m.refinement), true, {}, file);
  ASSERT_EQ(back.mesh.face_count(), m.refinement->mesh.face_count());
  int front = 0;
  for (const int f : m.region.faces) {
    std::array<std::array<double, 2>, 3> uv{};
    for (int k = 0; k < 3; ++k) uv[k] = back.texcoord0[back.corners[3 * static_cast<std::size_t>(f) + k]];
    const double cross = (uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1]) - (uv[1][1] - uv[0][1]) * (uv[2][0] - uv[0][0]);
    front += cross < 0.0 ? 1 : 0;
  }
  EXPECT_EQ(front, m.region.face_count());
}

// Under a memory budget the alternating run holds the refinement already made (to go back to) beside its own: its
// new vertices are charged against the budget's, and with no room left it does not run.
TEST(UvGuarantee, TheAlternatingRunsBoundLeavesRoomForTheRefinementItMayGoBackTo) {
  constexpr int kVertices = 961, kFaces = 1800;
  EXPECT_EQ(alternating_vertex_limit(kVertices, kFaces, kVertices, 0), kVertices + kFaces);  // no budget
  EXPECT_EQ(alternating_vertex_limit(kVertices, kFaces, kVertices, 16 * kVertices), kVertices + kFaces);
  EXPECT_EQ(alternating_vertex_limit(kVertices, kFaces, kVertices, 2000), 2000);   // the budget below the bound
  EXPECT_EQ(alternating_vertex_limit(kVertices, kFaces, 1500, 2000), 2000 - 539);  // 539 kept new vertices
  EXPECT_LE(alternating_vertex_limit(kVertices, kFaces, 2000, 2000), kVertices);   // no room: not run
}

// A flat unit square grid whose UVs are sheared along x by a smooth area-preserving map (x + 0.08 sin(2πy)), the
// two bottom corners pinned where the identity has them: the symmetric Dirichlet optimum is the identity (energy 4).
TEST(UvOptimization, ReachesTheIsometryOfAShearedPlane) {
  const TriangleMesh mesh = testing::flat_grid(16, 16, 1.0 / 16.0);
  std::vector<Point> uv;
  for (const Vec3& p : mesh.vertices) uv.emplace_back(p.x + 0.08 * std::sin(2.0 * M_PI * p.y), p.y);
  const std::vector<int> fixed = {0, 16};  // (0, 0) and (1, 0)
  const UvTriangleCheck positive = [](Point a, Point b, Point c) {
    return ((b - a).real() * (c - a).imag() - (b - a).imag() * (c - a).real()) > 0.0;
  };
  UvOptimizationOptions options;
  options.max_iterations = 200;
  options.relative_decrease = 1e-9;
  const UvOptimization r = optimize_uvs(mesh, uv, fixed, positive, options);
  EXPECT_GT(r.energy_before, 4.05);
  EXPECT_NEAR(r.energy_after, 4.0, 1e-5);
  double worst = 0.0;
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    worst = std::max(worst, std::abs(uv[v] - Point(mesh.vertices[v].x, mesh.vertices[v].y)));
  }
  EXPECT_LT(worst, 2e-3);
  EXPECT_EQ(uv[0], Point(0.0, 0.0));
  EXPECT_EQ(uv[16], Point(1.0, 0.0));
}

// σ1/σ2 and ‖J‖² + ‖J⁻¹‖² of a flat triangle's map to its UVs, computed here from the 2×2 Jacobian's singular values.
std::pair<double, double> aspect_and_energy(Point p0, Point p1, Point p2, Point q0, Point q1, Point q2) {
  const double s00 = (p1 - p0).real(), s01 = (p2 - p0).real(), s10 = (p1 - p0).imag(), s11 = (p2 - p0).imag();
  const double u00 = (q1 - q0).real(), u01 = (q2 - q0).real(), u10 = (q1 - q0).imag(), u11 = (q2 - q0).imag();
  const double sd = s00 * s11 - s01 * s10;
  // J = U S⁻¹.
  const double j00 = (u00 * s11 - u01 * s10) / sd, j01 = (u01 * s00 - u00 * s01) / sd;
  const double j10 = (u10 * s11 - u11 * s10) / sd, j11 = (u11 * s00 - u10 * s01) / sd;
  const double frob = j00 * j00 + j01 * j01 + j10 * j10 + j11 * j11;
  const double det = j00 * j11 - j01 * j10;
  const double disc = std::sqrt(std::max(frob * frob - 4.0 * det * det, 0.0));
  const double s1 = std::sqrt(0.5 * (frob + disc)), s2 = std::sqrt(0.5 * (frob - disc));
  return {s1 / s2, frob + frob / (det * det)};
}

// A unit grid whose UVs are the identity plus a smooth bump (up to 0.07 across, σ1/σ2 ≤ 1.39), held at a corner and
// at the bump's top: on the mean energy alone the triangles around the held top pinch (σ1/σ2 and the energy density
// rise above the start's worst, as on a 180 000-face sheet); with the default limits no triangle ends more
// distorted than the start's worst, and the mean still falls by more than 0.5 %.
TEST(UvOptimization, NoTriangleEndsMoreDistortedThanTheStartsWorst) {
  const TriangleMesh mesh = testing::flat_grid(24, 24, 1.0 / 24.0);
  std::vector<Point> start;
  for (const Vec3& p : mesh.vertices) {
    const Point z(p.x, p.y);
    start.push_back(z + Point(0.06, 0.04) * std::exp(-std::norm(z - Point(0.5, 0.5)) / 0.05));
  }
  const std::vector<int> fixed = {0, 12 * 25 + 12};
  const UvTriangleCheck positive = [](Point a, Point b, Point c) {
    return ((b - a).real() * (c - a).imag() - (b - a).imag() * (c - a).real()) > 0.0;
  };
  // The surface as SLIM sees it: scaled so that its area equals the UVs'.
  double flat = 0.0;
  for (const Face& f : mesh.faces) flat += 0.5 * std::abs(uv_doubled_area(start[f[0]], start[f[1]], start[f[2]]));
  const double scale = std::sqrt(flat);  // the grid's own area is 1
  const auto worst = [&](const std::vector<Point>& uv) {
    std::pair<double, double> w{0.0, 0.0};
    for (const Face& f : mesh.faces) {
      const auto at = [&](int v) { return scale * Point(mesh.vertices[v].x, mesh.vertices[v].y); };
      const auto [aspect, energy] = aspect_and_energy(at(f[0]), at(f[1]), at(f[2]), uv[f[0]], uv[f[1]], uv[f[2]]);
      w = {std::max(w.first, aspect), std::max(w.second, energy)};
    }
    return w;
  };
  const auto [aspect_before, energy_before] = worst(start);
  ASSERT_LT(aspect_before, 1.4);

  std::vector<Point> unlimited = start;
  UvOptimizationOptions mean_only;
  mean_only.limit_worst = false;
  const UvOptimization u = optimize_uvs(mesh, unlimited, fixed, positive, mean_only);
  EXPECT_GT(worst(unlimited).first, 1.1 * aspect_before) << "no pinch: the limits would not matter here";
  EXPECT_GT(worst(unlimited).second, energy_before);

  std::vector<Point> limited = start;
  const UvOptimization r = optimize_uvs(mesh, limited, fixed, positive);
  const auto [aspect_after, energy_after] = worst(limited);
  EXPECT_LE(energy_after, energy_before * (1.0 + 1e-9));
  EXPECT_LE(aspect_after, std::max(aspect_before, UvOptimizationOptions{}.max_aspect) * (1.0 + 1e-9));
  EXPECT_LT(r.energy_after, 0.995 * r.energy_before);
  EXPECT_GT(r.energy_after, u.energy_after);  // the limits cost some of the mean's decrease
  for (int v : fixed) EXPECT_EQ(limited[v], start[v]);
}

TEST(UvOptimization, RefusesAStartWithAFlippedTriangle) {
  const TriangleMesh mesh = testing::flat_grid(2, 2, 1.0);
  std::vector<Point> uv;
  for (const Vec3& p : mesh.vertices) uv.emplace_back(p.x, p.y);
  uv[4] = Point(3.0, 3.0);  // the centre pulled past the corner: triangles fold
  const UvTriangleCheck positive = [](Point a, Point b, Point c) {
    return ((b - a).real() * (c - a).imag() - (b - a).imag() * (c - a).real()) > 0.0;
  };
  EXPECT_THROW(optimize_uvs(mesh, uv, std::vector<int>{0}, positive), NumericalError);
}

// Thin triangles far from the origin of a 4096² texture: every triangle the margin accepts stays counter-clockwise
// after float32 rounding, and some positive in doubles do flip when rounded (so the margin is needed).
TEST(UvOrientation, TheMarginHoldsAgainstFloat32Rounding) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> base(0.0, 4096.0), unit(-1.0, 1.0), exponent(-4.0, -1.0);
  int accepted = 0, rounding_flips = 0;
  for (int i = 0; i < 200000; ++i) {
    const Point a(base(rng), base(rng));
    const double size = std::pow(10.0, exponent(rng));  // 1e-4 to 0.1 px
    const Point b = a + size * Point(unit(rng), unit(rng));
    const Point c = a + size * Point(unit(rng), unit(rng));
    const bool in_doubles = uv_doubled_area(a, b, c) > 0.0;
    const bool survives = positive_as_float32(a, b, c, 4096, 4096);
    if (uv_triangle_positive(a, b, c, 4096, 4096)) {
      ++accepted;
      ASSERT_TRUE(survives) << i;
    }
    if (in_doubles && !survives) ++rounding_flips;
  }
  EXPECT_GT(rounding_flips, 1000);
  EXPECT_GT(accepted, 100);
  // An ordinary triangle of a few pixels is accepted.
  EXPECT_TRUE(uv_triangle_positive(Point(10, 10), Point(12, 10), Point(10, 8), 512, 512));
  EXPECT_FALSE(uv_triangle_positive(Point(10, 10), Point(10, 8), Point(12, 10), 512, 512));
}

// Clustered pins whose warp turns faster than the grid resolves: bisection ends flip-free, but a pin's one-ring holds
// a triangle of σ1/σ2 624 (L² stretch 10.5). Held with the pin, as the faces around a pin are where the warp is smooth,
// it stayed so (10.5 after the optimisation). Now a pin's faces are held only when every face they touch is smooth,
// and the optimisation brings the region's stretch below 1.3 (Sander's L², measured independently of the energy).
TEST(UvGuarantee, APinsFacesAreHeldOnlyWhereTheWarpIsSmoothThere) {
  const Outcome o = refine_and_check(Case{16, 77.0, Pins::kCluster});
  ASSERT_TRUE(o.flip_free);
  const TextureMapping& m = o.mapping;
  ASSERT_TRUE(m.optimization && m.optimization->applied);
  EXPECT_FALSE(m.untangling && m.untangling->result.applied);  // the warp's own UVs, bisected: faces held by default
  EXPECT_GT(m.optimization->before.max_aspect, 100.0);
  const PinnedGrid g(16, 77.0, Pins::kCluster);  // the same mesh and texture size
  const MappingQuality q = evaluate_mapping(g.mesh, m, m.texture_px, g.options);
  EXPECT_LT(q.texture.l2_stretch, 0.2 * m.optimization->before.l2_stretch);
  EXPECT_LT(q.texture.l2_stretch, 1.3);
  // No face held whole (its corners all fixed, so as it started) is more than 16:1 anisotropic, unless its corners are
  // all pins: a face is held through corners that different pins' faces bring, too.
  std::vector<char> pin(m.texture_px.size(), 0);
  for (std::size_t i = 0; i < m.features.size(); ++i) pin[pin_vertex(g.mesh, m, i)] = 1;
  const std::vector<char> fixed = [&] {
    std::vector<char> f(m.texture_px.size(), 0);
    for (const int v : m.optimization->fixed) f[v] = 1;
    return f;
  }();
  const std::vector<Point> domain = pixels_to_domain(m.texture_px);
  for (const Face& f : m.region.local.faces) {
    if (!fixed[f[0]] || !fixed[f[1]] || !fixed[f[2]] || (pin[f[0]] && pin[f[1]] && pin[f[2]])) continue;
    const TriangleDistortion d =
        triangle_distortion(m.region.local.vertices[f[0]], m.region.local.vertices[f[1]], m.region.local.vertices[f[2]],
                            domain[f[0]], domain[f[1]], domain[f[2]]);
    EXPECT_LE(d.aspect, 16.0) << f[0] << " " << f[1] << " " << f[2];
  }
}

// A clustered pin set (±128 px) that untangling on the input's faces leaves with flipped faces (see below).
constexpr std::uint32_t kStuckSeed = 3;

// Where faces still flip (refinement off: triangles whose corners are all pins, their pins out of order), the
// optimisation works around them: their corners held, as many faces flipped after it as before, and its energy
// lowered (Sander's L² stretch of the whole region, flipped faces included, need not fall: on seed 3 it rose 0.3 %).
TEST(UvGuarantee, WhereFacesStillFlipTheOthersAreOptimisedAroundThem) {
  PinnedGrid g(kStuckSeed, 128.0, Pins::kCluster);
  g.options.refine = false;
  g.options.optimize = proto::UvOptimize::kStretch;
  const TextureMapping m = map_texture(g.backend, g.mesh, g.region, g.features, g.options);
  ASSERT_TRUE(m.untangling && m.optimization);
  const int flips = flipped_as_written(m);
  EXPECT_GT(flips, 0);
  EXPECT_EQ(flips, m.untangling->result.rejected_after);  // what untangling left, not one more or fewer
  EXPECT_TRUE(m.optimization->applied);
  EXPECT_LT(m.optimization->result.energy_after, m.optimization->result.energy_before);
  const MappingQuality q = evaluate_mapping(g.mesh, m, m.texture_px, g.options);
  EXPECT_EQ(q.texture.flipped, flips);
  // Every corner of a flipped face is held.
  for (const Face& f : m.region.local.faces) {
    const auto px = [&](int v) { return m.texture_px[v]; };
    if (uv_triangle_positive(px(f[0]), px(f[1]), px(f[2]), kTexture, kTexture)) continue;
    for (const int v : f) {
      EXPECT_TRUE(std::binary_search(m.optimization->fixed.begin(), m.optimization->fixed.end(), v)) << v;
    }
  }
}

}  // namespace
}  // namespace texwarp::mesh
