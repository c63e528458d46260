// Tests of the warp spec JSON codec: defaults, strictness (unknown keys, types, ranges) and error paths.
#include <gtest/gtest.h>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"

namespace texwarp::proto {
namespace {

WarpSpec decode(const std::string& text) { return decode_warp_spec(parse_json(text, "test.json")); }

// The InputError's place for a document that must be rejected.
std::string error_where(const std::string& text) {
  try {
    decode(text);
  } catch (const InputError& e) {
    return e.where().str();
  }
  return "(accepted)";
}

TEST(WarpSpecCodec, DecodesTheDocumentedExample) {
  const WarpSpec spec = decode(R"({"alpha": 3.0, "prealign": "none", "tolerance_px": 0.5,
    "features": [
      {"id": "nose", "source": [10, 20.5], "target": [11, 22]},
      {"id": "seam", "source": [1, 2], "target": [3, 4],
       "source_frame": {"angle_deg": 0, "scale": 1}, "target_frame": {"angle_deg": 30, "scale": 1.5}}]})");
  EXPECT_EQ(spec.alpha, 3.0);
  EXPECT_EQ(spec.prealign, Prealign::kNone);
  EXPECT_EQ(spec.tolerance_px, 0.5);
  ASSERT_EQ(spec.features.size(), 2u);
  EXPECT_EQ(spec.features[0].id, "nose");
  EXPECT_EQ(spec.features[0].source[1], 20.5);
  EXPECT_FALSE(spec.features[0].source_frame.has_value());
  ASSERT_TRUE(spec.features[1].target_frame.has_value());
  EXPECT_EQ(spec.features[1].target_frame->angle_deg, 30.0);
  EXPECT_EQ(spec.features[1].target_frame->scale, 1.5);
}

TEST(WarpSpecCodec, AppliesDefaults) {
  const WarpSpec spec = decode(R"({"features": [{"source": [1, 2], "target": [3, 4]}]})");
  EXPECT_EQ(spec.alpha, 2.0);
  EXPECT_EQ(spec.prealign, Prealign::kSimilarity);
  EXPECT_EQ(spec.tolerance_px, 0.01);
  EXPECT_EQ(spec.features[0].id, "");
}

TEST(WarpSpecCodec, RoundTripsThroughEncode) {
  const WarpSpec spec = decode(R"({"alpha": 1.5, "features": [{"id": "a", "source": [1, 2], "target": [3, 4],
    "source_frame": {"angle_deg": 10, "scale": 2}, "target_frame": {"angle_deg": -5, "scale": 0.5}}]})");
  const WarpSpec again = decode_warp_spec(encode_warp_spec(spec));
  EXPECT_EQ(again.alpha, 1.5);
  EXPECT_EQ(again.features[0].source_frame->scale, 2.0);
  EXPECT_EQ(again.features[0].target_frame->angle_deg, -5.0);
  EXPECT_EQ(again.features[0].id, "a");
}

TEST(WarpSpecCodec, RejectsUnknownKeysWithTheirPath) {
  EXPECT_EQ(error_where(R"({"features": [], "alhpa": 2})"), "$.alhpa");
  EXPECT_EQ(
      error_where(
          R"({"features": [{"source": [1, 2], "target": [3, 4]}, {"source": [1, 2], "target": [3, 4], "weight": 1}]})"),
      "$.features[1].weight");
  EXPECT_EQ(error_where(R"({"features": [{"source": [1, 2], "target": [3, 4], "source_frame": {"angle": 1},
    "target_frame": {}}]})"),
            "$.features[0].source_frame.angle");
}

TEST(WarpSpecCodec, RejectsWrongTypesAndShapes) {
  EXPECT_EQ(error_where(R"([])"), "$");
  EXPECT_EQ(error_where(R"({})"), "$.features");
  EXPECT_EQ(error_where(R"({"features": {}})"), "$.features");
  EXPECT_EQ(error_where(R"({"features": [{"source": [1], "target": [3, 4]}]})"), "$.features[0].source");
  EXPECT_EQ(error_where(R"({"features": [{"source": [1, "2"], "target": [3, 4]}]})"), "$.features[0].source[1]");
  EXPECT_EQ(error_where(R"({"features": [{"source": [1, 2]}]})"), "$.features[0].target");
  EXPECT_EQ(error_where(R"({"alpha": "2", "features": []})"), "$.alpha");
  EXPECT_EQ(error_where(R"({"prealign": "affine", "features": []})"), "$.prealign");
  EXPECT_EQ(error_where(R"({"features": [{"id": 7, "source": [1, 2], "target": [3, 4]}]})"), "$.features[0].id");
}

TEST(WarpSpecCodec, RejectsNumbersBeyondDouble) {
  // JSON has no NaN or infinity; 1e999 is the way to smuggle one in, and the parser refuses it.
  try {
    decode(R"({"features": [{"source": [1e999, 2], "target": [3, 4]}]})");
    FAIL() << "accepted 1e999";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), "test.json");
    EXPECT_NE(e.detail().find("number overflow"), std::string::npos) << e.detail();
  }
  EXPECT_EQ(error_where(R"({"tolerance_px": -1e999, "features": []})"), "test.json");
}

TEST(WarpSpecCodec, RejectsHalfGivenFramesAndBadScales) {
  EXPECT_EQ(error_where(R"({"features": [{"source": [1, 2], "target": [3, 4], "source_frame": {}}]})"),
            "$.features[0]");
  EXPECT_EQ(error_where(R"({"features": [{"source": [1, 2], "target": [3, 4], "source_frame": {},
    "target_frame": {"scale": 0}}]})"),
            "$.features[0].target_frame.scale");
}

TEST(WarpSpecCodec, SyntaxErrorsNameTheSourceAndOffset) {
  try {
    parse_json("{\"features\": [}", "f.json");
    FAIL() << "accepted broken JSON";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), "f.json");
    EXPECT_NE(e.detail().find("byte 15"), std::string::npos) << e.detail();
  }
}

TEST(WarpSpecCodec, DecodesPointLists) {
  const auto points = decode_points(parse_json("[[1, 2], [3.5, -4]]", "p"));
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[1][0], 3.5);
  EXPECT_EQ(points[1][1], -4.0);
  EXPECT_THROW(decode_points(parse_json("[[1, 2, 3]]", "p")), InputError);
  EXPECT_THROW(decode_points(parse_json("{\"points\": []}", "p")), InputError);
}

}  // namespace
}  // namespace texwarp::proto
