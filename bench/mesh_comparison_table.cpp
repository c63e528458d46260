// The comparison table (Seo & Cordier Table 1 style): L² stretch, L² shear, flips, max residual and UV time
// for this method (inverse warp of the LSCM embedding) and a thin-plate spline fitted on the same constraints
// (targets → sources), per mesh and over random feature sets. Prints Markdown (texwarp_bench_mesh_table).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <random>
#include <string>

#include "mesh_test_shapes.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/moving_least_squares.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/core/thin_plate_spline.hpp"
#include "texwarp/mesh/feature_placement.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/region_spec.hpp"
#include "texwarp/mesh/surface_feature_conversion.hpp"
#include "texwarp/mesh/texture_mapping.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"

namespace {

using namespace texwarp;
using namespace texwarp::mesh;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

struct Case {
  std::string name;
  TriangleMesh mesh;
  MeshRegion region;
  SurfaceFeatureSet features;
  TextureMappingOptions options;
};

// Features for a generated mesh: the region vertices nearest to a gx×gy grid of frame positions; sources
// = a similarity of the targets (scale 0.9, 0.1 rad about the centre) plus a random offset of up to
// `jitter` px per axis; the first feature (with_gradient) is a gradient feature twisted by 15° against that
// similarity, with the embedding's own texel density.
Case generated(const std::string& name, TriangleMesh mesh, double jitter, std::uint32_t seed, int nx = 4, int ny = 3,
               bool with_gradient = true) {
  Case c;
  c.name = name;
  c.mesh = std::move(mesh);
  c.region = whole_mesh_region(c.mesh, proto::InputLocation::file(name));
  c.options.texture_width = c.options.texture_height = 512;
  const LscmEmbedding e = lscm_embedding(c.region.local, c.region.boundary);
  const FramePlacement frame = place_in_frame(e.positions, {512, 512, c.options.margin_px, true});
  const Point centre(256, 256);
  const Point similarity = 0.9 * std::polar(1.0, 0.1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  // Grid inside the embedding's bounding box.
  double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
  for (Point p : frame.pixels) {
    lo_x = std::min(lo_x, p.real()), hi_x = std::max(hi_x, p.real());
    lo_y = std::min(lo_y, p.imag()), hi_y = std::max(hi_y, p.imag());
  }
  for (int gy = 0; gy < ny; ++gy) {
    for (int gx = 0; gx < nx; ++gx) {
      const Point g(lo_x + (hi_x - lo_x) * (0.15 + 0.7 * gx / (nx - 1.0)),
                    lo_y + (hi_y - lo_y) * (0.2 + 0.6 * gy / (ny - 1.0)));
      int best = 0;
      for (int i = 1; i < c.region.vertex_count(); ++i) {
        if (std::abs(frame.pixels[i] - g) < std::abs(frame.pixels[best] - g)) best = i;
      }
      SurfaceFeature f;
      f.target = VertexTarget{c.region.vertices[best]};
      f.source = centre + similarity * (frame.pixels[best] - centre) + Point(u(rng), u(rng));
      if (with_gradient && c.features.features.empty()) {
        // Direction: the world x axis; its frame image gives the angle the similarity would give it.
        const SurfaceFrame target{{1, 0, 0}, 1.0};
        int face = -1;
        for (int fi : c.region.faces) {
          for (int v : c.mesh.faces[fi]) {
            if (v == c.region.vertices[best] && face < 0) face = fi;
          }
        }
        const Frame natural =
            gradient_target_frame(c.mesh, c.region, frame.pixels, face, target, Frame{}, proto::JsonPath{});
        // natural.scale = |J d̂| (texels_per_unit 1): the density the similarity implies is 0.9·|J d̂|.
        f.source_frame = Frame{natural.angle_rad + std::arg(similarity) + 15.0 * std::acos(-1.0) / 180.0, 1.0};
        f.target_frame = SurfaceFrame{{1, 0, 0}, 0.9 * natural.scale};
      }
      c.features.features.push_back(f);
    }
  }
  return c;
}

Case spot() {
  Case c;
  c.name = "spot head (curve region)";
  const std::string examples = std::string(TEXWARP_SOURCE_DIR) + "/examples/mesh/";
  c.mesh = read_mesh_file(examples + "spot.obj");
  auto json = [](const std::string& p) { return proto::parse_json(read_text_file(p, 1 << 24), p); };
  c.region = select_region(c.mesh, proto::decode_region_spec(json(examples + "spot_head_region.json")),
                           proto::InputLocation::file("region"));
  c.features =
      surface_features_from_spec(proto::decode_surface_feature_set(json(examples + "spot_head_features.json")));
  const ImageHeader h = read_image_header(std::string(TEXWARP_SOURCE_DIR) + "/examples/astronaut.png");
  c.options.texture_width = h.width;
  c.options.texture_height = h.height;
  return c;
}

void row(const char* mesh, const char* method, int faces, std::size_t features, const MappingQuality& q, double ms) {
  std::printf("| %s | %d | %zu | %s | %.3f | %.3f | %d | %.3f | %.1f |\n", mesh, faces, features, method,
              q.texture.l2_stretch, q.texture.l2_shear, q.texture.flipped + q.texture.degenerate, q.max_residual_px,
              ms);
}

int run() {
  std::vector<Case> cases;
  cases.push_back(spot());
  cases.push_back(generated("sphere cap 75°", testing::sphere_cap(1.3, 24, 48), 12.0, 1));
  cases.push_back(generated("bumpy height field", testing::height_field(40, 0.025, 0.08, 0.5), 12.0, 2));
  cases.push_back(generated("bumpy height field, strong", testing::height_field(40, 0.025, 0.08, 0.5), 35.0, 3));
  cases.push_back(generated("cylinder strip 150°", testing::cylinder_strip(1.0, 2.6, 1.5, 40, 24), 20.0, 4));
  cases.push_back(
      generated("height field, 20 features, ±40 px", testing::height_field(40, 0.025, 0.08, 0.5), 40.0, 10, 5, 4));
  cases.push_back(
      generated("height field, 20 features, ±60 px", testing::height_field(40, 0.025, 0.08, 0.5), 60.0, 10, 5, 4));

  std::printf("| mesh | faces | features | method | L² stretch | L² shear | flipped+degenerate | max residual (px) | "
              "UV time (ms) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  CpuBackend backend;
  for (const Case& c : cases) {
    auto start = Clock::now();
    const TextureMapping m = map_texture(backend, c.mesh, c.region, c.features, c.options);
    const double total_ms = ms_since(start);
    const MappingQuality ours = evaluate_mapping(c.mesh, m, m.texture_px, c.options);

    // LSCM alone (UVs into the warped texture): the unconstrained embedding, for reference.
    MappingQuality lscm = evaluate_mapping(c.mesh, m, m.frame.pixels, c.options);
    for (std::size_t i = 0; i < m.features.size(); ++i) {
      lscm.residual_px[i] = std::abs(m.features[i].feature.target - m.features[i].feature.source);
    }
    lscm.max_residual_px = *std::max_element(lscm.residual_px.begin(), lscm.residual_px.end());

    start = Clock::now();
    std::vector<Point> targets, sources;
    for (const PlacedFeature& p : m.features) {
      targets.push_back(p.feature.target);
      sources.push_back(p.feature.source);
    }
    const ThinPlateSpline tps(targets, sources);
    std::vector<Point> tps_px(m.frame.pixels.size());
    for (std::size_t i = 0; i < tps_px.size(); ++i) tps_px[i] = tps(m.frame.pixels[i]);
    const double tps_ms = ms_since(start);
    const MappingQuality baseline = evaluate_mapping(c.mesh, m, tps_px, c.options);

    start = Clock::now();
    const MovingLeastSquares mls(targets, sources);
    std::vector<Point> mls_px(m.frame.pixels.size());
    for (std::size_t i = 0; i < mls_px.size(); ++i) mls_px[i] = mls(m.frame.pixels[i]);
    const double mls_ms = ms_since(start);
    const MappingQuality mls_quality = evaluate_mapping(c.mesh, m, mls_px, c.options);

    const char* name = c.name.c_str();
    row(name, "LSCM only (no constraints)", m.region.face_count(), m.features.size(), lscm, m.lscm_seconds * 1e3);
    row(name, "this method (warp)", m.region.face_count(), m.features.size(), ours, m.warp_seconds * 1e3);
    row(name, "thin-plate spline", m.region.face_count(), m.features.size(), baseline, tps_ms);
    row(name, "moving least squares", m.region.face_count(), m.features.size(), mls_quality, mls_ms);
    std::fprintf(stderr, "%s: pipeline %.1f ms (LSCM %.1f ms, vertex warp %.1f ms)\n", name, total_ms,
                 m.lscm_seconds * 1e3, m.warp_seconds * 1e3);
  }
  // Sweep: 20 random feature sets per displacement bound on the height field (20 features each).
  std::printf("\n| height field, 20 features | gradient feature | sets | method | sets without flips | "
              "flipped+degenerate: median (max) | L² stretch: median (max) | max residual (px) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const bool with_gradient : {true, false}) {
    for (const double jitter : {20.0, 40.0, 60.0}) {
      std::vector<double> flips[2], stretch[2];
      double worst_residual[2] = {0.0, 0.0};
      int refused = 0;
      for (std::uint32_t seed = 100; seed < 120; ++seed) {
        const Case c =
            generated("sweep", testing::height_field(40, 0.025, 0.08, 0.5), jitter, seed, 5, 4, with_gradient);
        try {
          const TextureMapping m = map_texture(backend, c.mesh, c.region, c.features, c.options);
          std::vector<Point> targets, sources;
          for (const PlacedFeature& p : m.features) {
            targets.push_back(p.feature.target);
            sources.push_back(p.feature.source);
          }
          const ThinPlateSpline tps(targets, sources);
          std::vector<Point> tps_px(m.frame.pixels.size());
          for (std::size_t i = 0; i < tps_px.size(); ++i) tps_px[i] = tps(m.frame.pixels[i]);
          const MappingQuality q[2] = {evaluate_mapping(c.mesh, m, m.texture_px, c.options),
                                       evaluate_mapping(c.mesh, m, tps_px, c.options)};
          for (int k = 0; k < 2; ++k) {
            flips[k].push_back(q[k].texture.flipped + q[k].texture.degenerate);
            stretch[k].push_back(q[k].texture.l2_stretch);
            worst_residual[k] = std::max(worst_residual[k], q[k].max_residual_px);
          }
        } catch (const InputError& e) {
          // Trajectories that would collide are planned, not refused (issue 13): what is left is a set the warp
          // cannot take at all (coincident sources or targets), named on stderr.
          ++refused;
          std::fprintf(stderr, "sweep ±%.0f px, seed %u: refused: %s\n", jitter, static_cast<unsigned>(seed), e.what());
        }
      }
      for (int k = 0; k < 2; ++k) {
        auto median = [](std::vector<double> v) {
          std::sort(v.begin(), v.end());
          return v.empty() ? 0.0 : v[v.size() / 2];
        };
        const auto zero = std::count(flips[k].begin(), flips[k].end(), 0.0);
        std::printf("| ±%.0f px | %s | %zu (%d refused) | %s | %ld | %.0f (%.0f) | %.3f (%.3f) | %.3f |\n", jitter,
                    with_gradient ? "yes" : "no", flips[k].size(), refused,
                    k == 0 ? "this method (warp)" : "thin-plate spline", static_cast<long>(zero), median(flips[k]),
                    flips[k].empty() ? 0.0 : *std::max_element(flips[k].begin(), flips[k].end()), median(stretch[k]),
                    stretch[k].empty() ? 0.0 : *std::max_element(stretch[k].begin(), stretch[k].end()),
                    worst_residual[k]);
      }
    }
  }
  return 0;
}

}  // namespace

int main() {
  try {
    return run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "texwarp_bench_mesh_table: %s\n", e.what());
    return 1;
  }
}
