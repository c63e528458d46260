// Surface features: the strict feature-file decoder, and placement in the embedding (face + barycentric,
// vertex, snapped point, gradient frames through the embedding's Jacobian), with their specific errors.
#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "input_error_text.hpp"
#include "mesh_test_shapes.hpp"
#include "texwarp/mesh/feature_placement.hpp"
#include "texwarp/mesh/frame_placement.hpp"
#include "texwarp/mesh/lscm.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/surface_feature_conversion.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"

namespace texwarp::mesh {
namespace {

using texwarp::testing::input_error_of;

using ::testing::HasSubstr;

SurfaceFeatureSet decode(const std::string& text) {
  return surface_features_from_spec(proto::decode_surface_feature_set(proto::parse_json(text, "f")));
}

TEST(SurfaceFeatureCodec, DecodesEveryTargetKindAndFrames) {
  const SurfaceFeatureSet set = decode(R"({
    "alpha": 1.5, "prealign": "none", "tolerance_px": 0.001, "snap_tolerance": 0.25,
    "features": [
      {"id": "a", "source": [1, 2], "target": {"face": 3, "barycentric": [0.2, 0.3, 0.5]}},
      {"source": [3, 4], "target": {"point": [1, 2, 3]}},
      {"source": [5, 6], "target": {"vertex": 7},
       "source_frame": {"angle_deg": 90, "scale": 2}, "target_frame": {"direction": [0, 1, 0], "texels_per_unit": 40}}
    ]})");
  EXPECT_EQ(set.options.alpha, 1.5);
  EXPECT_EQ(set.options.prealign, Prealign::kNone);
  EXPECT_EQ(set.options.tolerance_px, 0.001);
  EXPECT_EQ(set.snap_tolerance, 0.25);
  ASSERT_EQ(set.features.size(), 3u);
  const auto& face = std::get<FaceTarget>(set.features[0].target);
  EXPECT_EQ(set.features[0].id, "a");
  EXPECT_EQ(face.face, 3);
  EXPECT_DOUBLE_EQ(face.barycentric[2], 0.5);
  EXPECT_EQ(std::get<PointTarget>(set.features[1].target).point.z, 3.0);
  EXPECT_EQ(set.features[1].source, Point(3, 4));
  EXPECT_FALSE(set.features[1].is_gradient());
  const SurfaceFeature& g = set.features[2];
  EXPECT_EQ(std::get<VertexTarget>(g.target).vertex, 7);
  ASSERT_TRUE(g.is_gradient());
  EXPECT_DOUBLE_EQ(g.source_frame->angle_rad, std::numbers::pi / 2);
  EXPECT_EQ(g.source_frame->scale, 2.0);
  EXPECT_EQ(g.target_frame->direction.y, 1.0);
  EXPECT_EQ(g.target_frame->texels_per_unit, 40.0);
}

TEST(SurfaceFeatureCodec, ErrorsNameTheJsonPath) {
  auto error = [](const std::string& feature) {
    return input_error_of([&] { decode(R"({"features": [)" + feature + "]}"); });
  };
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"vertex": 1, "extra": 2}})"),
              HasSubstr("$.features[0].target.extra: unknown key"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"vertex": 1}, "weight": 2})"),
              HasSubstr("$.features[0].weight: unknown key"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"vertex": 1, "point": [0, 0, 0]}})"),
              HasSubstr("$.features[0].target: give exactly one"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {}})"),
              HasSubstr("$.features[0].target: expected a surface target"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": [1, 2]})"), HasSubstr("$.features[0].target: expected an object"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"face": 1}})"),
              HasSubstr("$.features[0].target.barycentric: required key is missing"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"face": 1, "barycentric": [0.5, 0.5, 0.5]}})"),
              HasSubstr("$.features[0].target.barycentric: barycentric weights must be ≥ 0 and sum to 1"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"face": 1, "barycentric": [1.5, -0.5, 0]}})"),
              HasSubstr("$.features[0].target.barycentric"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"face": -1, "barycentric": [1, 0, 0]}})"),
              HasSubstr("$.features[0].target.face: expected a 0-based id"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"vertex": 1.5}})"),
              HasSubstr("$.features[0].target.vertex: expected an integer"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"point": [0, 0]}})"),
              HasSubstr("$.features[0].target.point: expected [x, y, z]"));
  EXPECT_THAT(error(R"({"source": [0], "target": {"vertex": 1}})"),
              HasSubstr("$.features[0].source: expected a point"));
  EXPECT_THAT(error(R"({"source": [0, 0], "target": {"vertex": 1}, "source_frame": {}})"),
              HasSubstr("$.features[0]: a gradient feature needs both source_frame and target_frame"));
  const std::string frames = R"({"source": [0, 0], "target": {"vertex": 1}, "source_frame": {}, "target_frame": )";
  EXPECT_THAT(error(frames + R"({"direction": [0, 0, 0], "texels_per_unit": 1}})"),
              HasSubstr("$.features[0].target_frame.direction: the direction must not be zero"));
  EXPECT_THAT(error(frames + R"({"direction": [1, 0, 0], "texels_per_unit": 0}})"),
              HasSubstr("$.features[0].target_frame.texels_per_unit: must be > 0"));
  EXPECT_THAT(error(frames + R"({"direction": [1, 0, 0]}})"),
              HasSubstr("$.features[0].target_frame.texels_per_unit: required key is missing"));
  EXPECT_THAT(error(frames + R"({"direction": [1, 0, 0], "texels_per_unit": 2, "angle_deg": 3}})"),
              HasSubstr("$.features[0].target_frame.angle_deg: unknown key"));
  EXPECT_THAT(input_error_of([] { decode(R"({"features": [], "prealign": "affine"})"); }),
              HasSubstr("$.prealign: expected"));
  EXPECT_THAT(input_error_of([] { decode(R"({"features": [], "snap_tolerance": -1})"); }),
              HasSubstr("$.snap_tolerance: must be ≥ 0"));
  EXPECT_THAT(input_error_of([] { decode(R"({"feature": []})"); }), HasSubstr("$.features: required key is missing"));
}

// A flat 10×8 grid (step 0.1, z = 0) without its last column of cells in the region, embedded by LSCM
// and placed into a 400×300 frame.
struct FlatScene {
  TriangleMesh mesh = testing::flat_grid(10, 8, 0.1);
  MeshRegion region;
  FramePlacement frame;
  FlatScene() {
    std::vector<int> faces;
    for (int f = 0; f < mesh.face_count(); ++f) {
      if ((f / 2) % 10 != 9) faces.push_back(f);
    }
    region = disk_region(mesh, faces, proto::InputLocation::file("flat"));
    const LscmEmbedding e = lscm_embedding(region.local, region.boundary);
    frame = place_in_frame(e.positions, {400, 300, 10.0, true});
  }
  Point px(int mesh_vertex) const { return frame.pixels[region.local_vertex[mesh_vertex]]; }
  std::vector<PlacedFeature> place(const std::string& features) const {
    return place_surface_features(mesh, region, frame.pixels, decode(features));
  }
};

TEST(FeaturePlacement, TargetsLandWhereTheEmbeddingPutsThem) {
  const FlatScene s;
  const auto placed = s.place(R"({"features": [
      {"source": [1, 1], "target": {"face": 24, "barycentric": [0.2, 0.3, 0.5]}},
      {"source": [2, 2], "target": {"vertex": 40}},
      {"source": [3, 3], "target": {"point": [0.43, 0.27, 0.0001]}}]})");
  const Face& f = s.mesh.faces[24];
  EXPECT_LT(std::abs(placed[0].feature.target - (0.2 * s.px(f[0]) + 0.3 * s.px(f[1]) + 0.5 * s.px(f[2]))), 1e-12);
  EXPECT_EQ(placed[0].feature.source, Point(1, 1));
  EXPECT_EQ(placed[1].feature.target, s.px(40));
  EXPECT_EQ(placed[1].location.barycentric[0] + placed[1].location.barycentric[1] + placed[1].location.barycentric[2],
            1.0);
  // The point snaps 1e-4 down onto the plane; the embedding of a flat grid is a similarity, so its target is
  // that similarity applied to (0.43, 0.27): compare with the bilinear position from the cell's corners.
  EXPECT_NEAR(placed[2].snap_distance, 1e-4, 1e-15);
  EXPECT_NEAR(placed[2].position.x, 0.43, 1e-12);
  EXPECT_NEAR(placed[2].position.y, 0.27, 1e-12);
  auto id = [](int i, int j) { return j * 11 + i; };
  const Point p00 = s.px(id(4, 2)), p10 = s.px(id(5, 2)), p01 = s.px(id(4, 3));
  const Point expected = p00 + 0.3 * (p10 - p00) + 0.7 * (p01 - p00);
  EXPECT_LT(std::abs(placed[2].feature.target - expected), 1e-9);
}

TEST(FeaturePlacement, GradientFrameComesFromTheEmbeddingJacobian) {
  const FlatScene s;
  const auto placed = s.place(R"({"features": [
      {"source": [5, 5], "target": {"vertex": 40},
       "source_frame": {"angle_deg": 30, "scale": 2}, "target_frame": {"direction": [1, 1, 0.5], "texels_per_unit": 250}}]})");
  ASSERT_TRUE(placed[0].feature.is_gradient());
  // Independently: the embedding is a similarity; the image of the tangent direction (1, 1)/√2 is the image
  // of the diagonal from vertex (i, j) to (i+1, j+1), per world unit of length.
  auto id = [](int i, int j) { return j * 11 + i; };
  const Point diagonal = (s.px(id(5, 4)) - s.px(id(4, 3))) / (0.1 * std::sqrt(2.0));
  const Frame& t = *placed[0].feature.target_frame;
  EXPECT_NEAR(t.angle_rad, std::arg(diagonal), 1e-9);
  EXPECT_NEAR(t.scale, 2.0 * std::abs(diagonal) / 250.0, 1e-9);
  EXPECT_NEAR(std::abs(diagonal), s.frame.pixels_per_unit, 1e-6);
  EXPECT_DOUBLE_EQ(placed[0].feature.source_frame->angle_rad, std::numbers::pi / 6);
}

TEST(FeaturePlacement, ErrorsNameTheFeature) {
  const FlatScene s;
  EXPECT_THAT(input_error_of([&] {
                s.place(R"({"features": [{"source": [0, 0], "target": {"face": 18, "barycentric": [1, 0, 0]}}]})");
              }),
              HasSubstr("$.features[0].target.face: face 18 is not in the region"));
  EXPECT_THAT(input_error_of([&] {
                s.place(R"({"features": [{"source": [0, 0], "target": {"face": 999, "barycentric": [1, 0, 0]}}]})");
              }),
              HasSubstr("$.features[0].target.face: face 999 does not exist (the mesh has 160 faces)"));
  EXPECT_THAT(
      input_error_of([&] {
        s.place(
            R"({"features": [{"source": [0, 0], "target": {"vertex": 0}}, {"source": [1, 0], "target": {"vertex": 10}}]})");
      }),
      HasSubstr("$.features[1].target.vertex: vertex 10 is not in the region"));
  EXPECT_THAT(input_error_of([&] { s.place(R"({"features": [{"source": [0, 0], "target": {"vertex": 500}}]})"); }),
              HasSubstr("$.features[0].target.vertex: vertex 500 does not exist"));
  // The region's diagonal is √(0.9² + 0.8²) ≈ 1.204: default snap tolerance 1% of it.
  EXPECT_THAT(
      input_error_of([&] { s.place(R"({"features": [{"source": [0, 0], "target": {"point": [0.4, 0.4, 0.05]}}]})"); }),
      HasSubstr("$.features[0].target.point: the point is 0.05 from the region's surface"));
  EXPECT_EQ(
      input_error_of([&] {
        s.place(R"({"snap_tolerance": 0.06, "features": [{"source": [0, 0], "target": {"point": [0.4, 0.4, 0.05]}}]})");
      }),
      "");
  EXPECT_THAT(
      input_error_of([&] { s.place(R"({"features": [{"source": [0, 0], "target": {"point": [0.95, 0.4, 0]}}]})"); }),
      HasSubstr("from the region's surface"));  // on the mesh, but in the column left out of the region
  EXPECT_THAT(input_error_of([&] {
                s.place(R"({"features": [{"source": [0, 0], "target": {"vertex": 40}, "source_frame": {},
                            "target_frame": {"direction": [0, 0, 1], "texels_per_unit": 3}}]})");
              }),
              HasSubstr("$.features[0].target_frame: the direction is (nearly) normal to the surface"));
}

}  // namespace
}  // namespace texwarp::mesh
