// The texture-mapping pipeline end to end through the library: per-vertex UVs meet the features within a
// pixel, no UV triangle flips, a gradient feature gets its direction and texel density, the warped texture
// shows each feature's texel at its target, and the OBJ carries the same UVs.
#include <cmath>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mesh_test_shapes.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/mapping_report.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/obj_output.hpp"
#include "texwarp/mesh/region_spec.hpp"
#include "texwarp/mesh/surface_feature_conversion.hpp"
#include "texwarp/mesh/texture_mapping.hpp"
#include "texwarp/mesh/uv_convention.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"

namespace texwarp::mesh {
namespace {

using ::testing::HasSubstr;

const std::string kSpot = std::string(TEXWARP_SOURCE_DIR) + "/examples/mesh/spot.obj";
const std::string kTexture = std::string(TEXWARP_SOURCE_DIR) + "/examples/astronaut.png";
const std::string kExamples = std::string(TEXWARP_SOURCE_DIR) + "/examples/mesh/";

nlohmann::json read_json(const std::string& path) { return proto::parse_json(read_text_file(path, 1 << 24), path); }

struct SpotCase {
  TriangleMesh mesh = read_mesh_file(kSpot);
  MeshRegion region = select_region(mesh, proto::decode_region_spec(read_json(kExamples + "spot_head_region.json")),
                                    proto::InputLocation::file("region"));
  SurfaceFeatureSet features =
      surface_features_from_spec(proto::decode_surface_feature_set(read_json(kExamples + "spot_head_features.json")));
  TextureMappingOptions options;
  SpotCase() {
    const ImageHeader header = read_image_header(kTexture);
    options.texture_width = header.width;
    options.texture_height = header.height;
  }
};

// Barycentric interpolation of per-region-vertex positions at a placed feature.
Point at_feature(const TriangleMesh& mesh, const TextureMapping& m, const PlacedFeature& p,
                 std::span<const Point> values) {
  const Face& f = mesh.faces[p.location.face];
  Point q(0, 0);
  for (int k = 0; k < 3; ++k) q += p.location.barycentric[k] * values[m.region.local_vertex[f[k]]];
  return q;
}

TEST(TextureMapping, SpotHeadMeetsItsFeaturesWithoutFlips) {
  const SpotCase c;
  ASSERT_GE(c.features.features.size(), 10u);
  CpuBackend backend;
  const TextureMapping m = map_texture(backend, c.mesh, c.region, c.features, c.options);
  const MappingQuality q = evaluate_mapping(c.mesh, m, m.texture_px, c.options, true);
  ASSERT_EQ(q.residual_px.size(), c.features.features.size());
  int gradients = 0;
  for (std::size_t i = 0; i < m.features.size(); ++i) {
    const PlacedFeature& p = m.features[i];
    gradients += p.feature.is_gradient() ? 1 : 0;
    // Independent: interpolate the texture positions here and compare with the source.
    const double r = std::abs(at_feature(c.mesh, m, p, m.texture_px) - p.feature.source);
    EXPECT_NEAR(q.residual_px[i], r, 1e-12);
    EXPECT_LE(r, 1.0) << "feature " << i;
    if (std::holds_alternative<VertexTarget>(c.features.features[i].target)) {
      EXPECT_LE(r, 0.02) << "feature " << i;
    }
    // Through the UVs into the warped texture the features are exact: those UVs are the embedding itself.
    EXPECT_LT(std::abs(at_feature(c.mesh, m, p, m.frame.pixels) - p.feature.target), 1e-9);
  }
  EXPECT_GE(gradients, 1);
  EXPECT_LE(q.max_residual_px, 1.0);
  EXPECT_EQ(q.texture.flipped, 0);
  EXPECT_EQ(q.texture.degenerate, 0);
  EXPECT_EQ(q.frame.flipped, 0);
  EXPECT_EQ(q.vertices_outside_texture, 0);
  EXPECT_GE(q.texture.l2_stretch, 1.0);
  EXPECT_LT(q.texture.l2_stretch, 10.0);
  EXPECT_GT(q.texture.l2_shear, 0.0);
  EXPECT_LT(q.texture.l2_shear, 0.5);
  EXPECT_EQ(q.texture.per_triangle.size(), static_cast<std::size_t>(m.region.face_count()));
  std::printf("spot head: %d faces, %zu features: L2 stretch %.4f (warped UVs %.4f), L2 shear %.4f (%.4f), "
              "flips %d, max residual %.4f px, mean %.4f px\n",
              m.region.face_count(), m.features.size(), q.texture.l2_stretch, q.frame.l2_stretch, q.texture.l2_shear,
              q.frame.l2_shear, q.texture.flipped, q.max_residual_px, q.mean_residual_px);
}

TEST(TextureMapping, GradientFeatureGetsItsDirectionAndDensity) {
  SpotCase c;
  c.features.options.tolerance_px = 1e-10;  // so that a finite difference of the map is meaningful
  CpuBackend backend;
  const TextureMapping m = map_texture(backend, c.mesh, c.region, c.features, c.options);
  for (std::size_t i = 0; i < m.features.size(); ++i) {
    if (!c.features.features[i].is_gradient()) continue;
    const PlacedFeature& p = m.features[i];
    const SurfaceFrame& want = *c.features.features[i].target_frame;
    const Frame& source_frame = *c.features.features[i].source_frame;
    // The frame image of the unit tangent along the wanted direction (frame px per world unit), then the
    // texture displacement per world unit along it, by central differences of the exact inverse map.
    const Face& f = c.mesh.faces[p.location.face];
    Vec3 n = cross(c.mesh.vertices[f[1]] - c.mesh.vertices[f[0]], c.mesh.vertices[f[2]] - c.mesh.vertices[f[0]]);
    n = n / norm(n);
    Vec3 d = want.direction - dot(want.direction, n) * n;
    d = d / norm(d);
    const Point t =
        map_tangent(c.mesh.vertices[f[0]], c.mesh.vertices[f[1]], c.mesh.vertices[f[2]],
                    m.frame.pixels[m.region.local_vertex[f[0]]], m.frame.pixels[m.region.local_vertex[f[1]]],
                    m.frame.pixels[m.region.local_vertex[f[2]]], d);
    // A small step: with 11 positional features the gradient's own field dominates only within about a
    // pixel of it (its weight d^−α against the pairs' d^−2α, DESIGN.md §1), so the map bends quickly there;
    // measured relative error of the central difference: 28 % at 2 px, 3.7 % at 0.5 px, 0.005 % at 0.02 px.
    const double eps = 0.02 / std::abs(t);
    std::vector<Point> pts = {p.feature.target + eps * t, p.feature.target - eps * t};
    map_points(backend, *m.problem, pts, Direction::kInverse);
    const Point per_unit = (pts[0] - pts[1]) / (2.0 * eps);
    const Point expected = want.texels_per_unit * std::polar(1.0, source_frame.angle_rad);
    EXPECT_LT(std::abs(per_unit - expected), 1e-3 * want.texels_per_unit)
        << "got " << per_unit << ", expected " << expected;
  }
}

TEST(TextureMapping, WarpedTextureShowsEachFeaturesTexelAtItsTarget) {
  // The spot case at a quarter of the size (texture 128², sources / 4) with a smooth synthetic texture.
  SpotCase c;
  for (SurfaceFeature& f : c.features.features) f.source /= 4.0;
  c.options.texture_width = c.options.texture_height = 128;
  c.options.margin_px = 2.0;
  Image texture(128, 128, 1);
  for (int y = 0; y < 128; ++y) {
    for (int x = 0; x < 128; ++x) {
      texture.pixel(x, y)[0] = static_cast<float>(0.5 + 0.25 * std::sin((x + 0.5) / 9.0) * std::cos((y + 0.5) / 7.0));
    }
  }
  CpuBackend backend;
  const TextureMapping m = map_texture(backend, c.mesh, c.region, c.features, c.options);
  ImageWarpOptions options;
  options.width = options.height = 128;
  options.border = Border::kClamp;
  const Image warped = warp_image(backend, *m.problem, texture, options);
  for (const PlacedFeature& p : m.features) {
    float in = 0.0f, out = 0.0f;
    sample_image(texture, p.feature.source, Interpolation::kBilinear, Border::kClamp, &in);
    sample_image(warped, p.feature.target, Interpolation::kBilinear, Border::kClamp, &out);
    // Positional features: measured within 7.5e-4 of the texture's 0.25 amplitude. The gradient feature gets
    // a looser bound: its own field dominates only within about a pixel of it (weight d^−α against the
    // pairs' d^−2α), so the map bends inside the bilinear footprint (measured 1.7e-3 off here).
    EXPECT_NEAR(out, in, p.feature.is_gradient() ? 2e-2 : 5e-3) << p.feature.id;
  }
  const MappingQuality q = evaluate_mapping(c.mesh, m, m.texture_px, c.options);
  EXPECT_EQ(q.texture.flipped, 0);
  EXPECT_LE(q.max_residual_px, 1.0);
}

TEST(TextureMapping, ObjCarriesTheUvsInTheChosenConvention) {
  const SpotCase c;
  CpuBackend backend;
  const TextureMapping m = map_texture(backend, c.mesh, c.region, c.features, c.options);
  for (const UvOrigin origin : {UvOrigin::kBottomLeft, UvOrigin::kTopLeft}) {
    std::vector<std::array<double, 2>> uvs;
    for (const Point& px : m.texture_px) uvs.push_back(pixel_to_uv(px, 512, 512, origin));
    const std::string text = textured_obj_text(c.mesh, m.region, uvs, "test");
    // Read the vt lines and the f v/vt lines back by hand, and interpolate the UVs at each feature.
    std::vector<std::array<double, 2>> vt;
    std::map<int, std::array<int, 3>> vt_of_face;  // mesh face → its vt ids (0-based)
    std::istringstream in(text);
    int face = -1;
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("vt ", 0) == 0) {
        std::array<double, 2> uv{};
        std::sscanf(line.c_str(), "vt %lf %lf", uv.data(), &uv[1]);
        vt.push_back(uv);
      } else if (line.rfind("f ", 0) == 0) {
        ++face;
        int v[3], t[3];
        if (std::sscanf(line.c_str(), "f %d/%d %d/%d %d/%d", &v[0], &t[0], &v[1], &t[1], &v[2], &t[2]) == 6) {
          vt_of_face[face] = {t[0] - 1, t[1] - 1, t[2] - 1};
          EXPECT_EQ(c.mesh.faces[face], (Face{v[0] - 1, v[1] - 1, v[2] - 1}));
        }
      }
    }
    ASSERT_EQ(vt.size(), static_cast<std::size_t>(m.region.vertex_count()));
    ASSERT_EQ(vt_of_face.size(), static_cast<std::size_t>(m.region.face_count()));
    for (const PlacedFeature& p : m.features) {
      const auto& ids = vt_of_face.at(p.location.face);
      double u = 0, v = 0;
      for (int k = 0; k < 3; ++k) {
        u += p.location.barycentric[k] * vt[ids[k]][0];
        v += p.location.barycentric[k] * vt[ids[k]][1];
      }
      // DESIGN.md §3: u = x / width; v = 1 − y / height (bottom_left) or y / height (top_left).
      const double x = u * 512.0;
      const double y = (origin == UvOrigin::kBottomLeft ? 1.0 - v : v) * 512.0;
      EXPECT_LE(std::abs(Point(x, y) - p.feature.source), 1.0) << p.feature.id;
    }
  }
}

TEST(TextureMapping, ReportCarriesTheRequiredFields) {
  const SpotCase c;
  CpuBackend backend;
  const TextureMapping m = map_texture(backend, c.mesh, c.region, c.features, c.options);
  const MappingQuality q = evaluate_mapping(c.mesh, m, m.texture_px, c.options, true);
  MappingReportOptions ro;
  ro.per_triangle = true;
  ro.per_vertex = true;
  const nlohmann::json r = mapping_report(c.mesh, m, q, c.options, ro);
  EXPECT_EQ(r.at("uv_origin"), "bottom_left");
  EXPECT_EQ(r.at("l2_stretch").get<double>(), q.texture.l2_stretch);
  EXPECT_EQ(r.at("l2_shear").get<double>(), q.texture.l2_shear);
  EXPECT_EQ(r.at("flipped_triangles").get<int>(), 0);
  EXPECT_EQ(r.at("max_residual_px").get<double>(), q.max_residual_px);
  ASSERT_EQ(r.at("features").size(), m.features.size());
  EXPECT_EQ(r.at("features")[4].at("id"), "f05");
  EXPECT_EQ(r.at("features")[4].at("residual_px").get<double>(), q.residual_px[4]);
  EXPECT_EQ(r.at("triangles").size(), static_cast<std::size_t>(m.region.face_count()));
  ASSERT_EQ(r.at("vertices").size(), static_cast<std::size_t>(m.region.vertex_count()));
  const auto& v0 = r.at("vertices")[0];
  EXPECT_EQ(v0.at("vertex").get<int>(), m.region.vertices[0]);
  EXPECT_NEAR(v0.at("uv")[0].get<double>(), m.texture_px[0].real() / 512.0, 1e-15);
  EXPECT_NEAR(v0.at("uv")[1].get<double>(), 1.0 - m.texture_px[0].imag() / 512.0, 1e-15);
}

TEST(TextureMapping, FlatGridIsExactAndWithoutFeaturesTheIdentity) {
  // A flat rectangle, texture 200×160, no features: the texture positions are the frame positions.
  const TriangleMesh grid = testing::flat_grid(20, 16, 0.05);
  TextureMappingOptions o;
  o.texture_width = 200;
  o.texture_height = 160;
  o.margin_px = 0.0;
  CpuBackend backend;
  const TextureMapping id =
      map_texture(backend, grid, whole_mesh_region(grid, proto::InputLocation::file("g")), SurfaceFeatureSet{}, o);
  for (std::size_t i = 0; i < id.texture_px.size(); ++i) EXPECT_EQ(id.texture_px[i], id.frame.pixels[i]);
  const MappingQuality q = evaluate_mapping(grid, id, id.texture_px, o);
  EXPECT_NEAR(q.texture.l2_stretch, 1.0, 1e-9);  // a flat mesh, embedded by a similarity
  EXPECT_NEAR(q.texture.l2_shear, 0.0, 1e-9);
  // The 1.0 × 0.8 rectangle fills the 200×160 frame exactly (aspect kept, no margin).
  double max_x = 0, max_y = 0;
  for (Point p : id.frame.pixels) {
    max_x = std::max(max_x, p.real());
    max_y = std::max(max_y, p.imag());
  }
  EXPECT_NEAR(max_x, 200.0, 1e-9);
  EXPECT_NEAR(max_y, 160.0, 1e-9);
}

TEST(TextureMapping, RefusesCollidingFeatures) {
  SpotCase c;
  c.features.features[1].target = VertexTarget{2014};  // the same place as feature 0, another source
  CpuBackend backend;
  try {
    map_texture(backend, c.mesh, c.region, c.features, c.options);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("features[1]"));
  }
}

TEST(UvConvention, BottomLeftAndTopLeft) {
  const auto bl = pixel_to_uv(Point(50, 30), 200, 100, UvOrigin::kBottomLeft);
  EXPECT_DOUBLE_EQ(bl[0], 0.25);
  EXPECT_DOUBLE_EQ(bl[1], 0.7);
  const auto tl = pixel_to_uv(Point(50, 30), 200, 100, UvOrigin::kTopLeft);
  EXPECT_DOUBLE_EQ(tl[1], 0.3);
  EXPECT_LT(std::abs(uv_to_pixel(bl, 200, 100, UvOrigin::kBottomLeft) - Point(50, 30)), 1e-12);
  EXPECT_EQ(proto::parse_enum<UvOrigin>("top_left", {}), UvOrigin::kTopLeft);
  EXPECT_THROW(proto::parse_enum<UvOrigin>("bottom-left", {}), InputError);
}

}  // namespace
}  // namespace texwarp::mesh
