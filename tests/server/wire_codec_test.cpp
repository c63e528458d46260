// The job wire format (proto/): base64, the job codec's defaults, canonical form and strictness (every refusal
// names the JSON path), and the response codecs' round trips.
#include <gtest/gtest.h>

#include "texwarp/proto/base64.hpp"
#include "texwarp/proto/blob_info_codec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {
namespace {

const std::string kBlob = "sha256:" + std::string(64, 'a');

std::string where_rejected(const std::string& text) {
  try {
    decode_job_spec(parse_json(text, "test"));
  } catch (const InputError& e) {
    return e.where().str();
  }
  return "(accepted)";
}

std::string with_image(const std::string& rest) { return R"({"image": {"blob": ")" + kBlob + R"("}, )" + rest + "}"; }

TEST(Base64, RoundTripsEveryLengthAndByte) {
  std::string bytes;
  for (int i = 0; i < 300; ++i) {
    bytes.push_back(static_cast<char>(i * 37 % 256));
    EXPECT_EQ(base64_decode(base64_encode(bytes), JsonPath{}), bytes) << "length " << bytes.size();
  }
  EXPECT_EQ(base64_encode("Man"), "TWFu");
  EXPECT_EQ(base64_encode("Ma"), "TWE=");
  EXPECT_EQ(base64_encode("M"), "TQ==");
  EXPECT_EQ(base64_decode("TW\nFu", JsonPath{}), "Man");  // line breaks are skipped
}

TEST(Base64, RejectsWhatIsNotBase64WithThePath) {
  for (const char* bad : {"TWF", "TW=u", "T===", "TWFu!", "TQ==TQ=="}) {
    try {
      base64_decode(bad, JsonPath{"image", "base64"});
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where().str(), "$.image.base64") << bad;
    }
  }
}

TEST(JobSpecCodec, DecodesAnImageJobWithDefaults) {
  const JobSpec spec = decode_job_spec(
      parse_json(with_image(R"("warp": {"features": [{"source": [1, 2], "target": [3, 4]}]})"), "test"));
  EXPECT_EQ(spec.kind(), JobKind::kImage);
  EXPECT_EQ(spec.image.kind, ImageSourceSpec::Kind::kBlob);
  EXPECT_EQ(spec.image.blob, kBlob);
  ASSERT_TRUE(spec.warp);
  EXPECT_EQ(spec.warp->features.size(), 1u);
  EXPECT_EQ(spec.output.file_format, FileFormat::kPng);
  EXPECT_EQ(spec.output.interpolation, Interpolation::kBilinear);
  EXPECT_EQ(spec.output.width, 0);
  EXPECT_TRUE(spec.output.image);
  EXPECT_FALSE(spec.options.exact);
  EXPECT_EQ(spec.options.tolerance_px, 0.05);
  EXPECT_FALSE(spec.options.device);
}

TEST(JobSpecCodec, CanonicalFormRoundTrips) {
  const std::string text = R"({"name": "n", "image": {"base64": "aGVsbG8="},
    "warp": {"alpha": 3, "prealign": "none", "tolerance_px": 0.5,
             "features": [{"id": "g", "source": [1, 2], "target": [3, 4],
                           "source_frame": {"angle_deg": 10, "scale": 2}, "target_frame": {"angle_deg": 20, "scale": 1}}]},
    "output": {"width": 100, "height": 50, "interpolation": "bicubic", "border": "repeat", "pixel_format": "half",
               "file_format": "exr", "uv_origin": "top_left"},
    "options": {"exact": true, "tolerance_px": 0.2, "device": "opencl:pocl", "jacobian_check": true}})";
  const JobSpec spec = decode_job_spec(parse_json(text, "test"));
  EXPECT_EQ(spec.image.data, "hello");
  const nlohmann::json canonical = encode_job_spec(spec);
  const JobSpec again = decode_job_spec(canonical);
  EXPECT_EQ(encode_job_spec(again), canonical);
  EXPECT_EQ(canonical["image"]["base64"], "aGVsbG8=");
  EXPECT_EQ(canonical["output"]["width"], 100);
  EXPECT_EQ(canonical["output"]["pixel_format"], "half");
  EXPECT_EQ(canonical["options"]["device"], "opencl:pocl");
  EXPECT_EQ(canonical["options"]["tolerance_px"], 0.2);
  EXPECT_EQ(spec.options.tolerance_px, 0.2);
  EXPECT_EQ(canonical["warp"]["features"][0]["target_frame"]["angle_deg"], 20.0);
}

TEST(JobSpecCodec, MeshJobDecodesItsMeshRegionAndFeatures) {
  const JobSpec spec = decode_job_spec(parse_json(with_image(R"("mesh": {
      "source": {"inline": {"vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1,2]]}},
      "region": {"faces": [0]}, "features": {"features": []}, "margin_px": 4, "obj_uv": "warped"})"),
                                                  "t"));
  ASSERT_TRUE(spec.mesh);
  EXPECT_EQ(spec.kind(), JobKind::kMesh);
  EXPECT_EQ(spec.mesh->source.kind, MeshSourceSpec::Kind::kInline);
  EXPECT_EQ(spec.mesh->source.mesh.triangles[0][2], 2);
  EXPECT_EQ(spec.mesh->region->faces[0], 0);
  EXPECT_EQ(spec.mesh->margin_px, 4.0);
  EXPECT_EQ(spec.mesh->obj_uv, ObjUv::kWarped);
  const JobSpec again = decode_job_spec(encode_job_spec(spec));
  EXPECT_EQ(encode_job_spec(again), encode_job_spec(spec));
}

TEST(JobSpecCodec, RefusalsNameTheOffendingPath) {
  const std::string warp = R"("warp": {"features": []})";
  EXPECT_EQ(where_rejected("[]"), "$");
  EXPECT_EQ(where_rejected(R"({"warp": {"features": []}})"), "$");  // neither "image" nor "images"
  EXPECT_EQ(where_rejected(with_image(R"("colour": 1, )" + warp)), "$.colour");
  EXPECT_EQ(where_rejected(R"({"image": {}, )" + warp + "}"), "$.image");
  EXPECT_EQ(where_rejected(R"({"image": {"blob": ")" + kBlob + R"(", "path": "/x"}, )" + warp + "}"), "$.image.path");
  EXPECT_EQ(where_rejected(R"({"image": {"blob": "sha256:XYZ"}, )" + warp + "}"), "$.image.blob");
  EXPECT_EQ(where_rejected(R"({"image": {"base64": "@@@@"}, )" + warp + "}"), "$.image.base64");
  EXPECT_EQ(where_rejected(R"({"image": {"path": ""}, )" + warp + "}"), "$.image.path");
  EXPECT_EQ(where_rejected(with_image(R"("name": 1, )" + warp)), "$.name");
  EXPECT_EQ(where_rejected(with_image(R"("name": ")" + std::string(201, 'x') + R"(", )" + warp)), "$.name");
  EXPECT_EQ(where_rejected(with_image(R"("x": 0)")), "$");  // neither warp nor mesh
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "mesh": {})")), "$.mesh");
  EXPECT_EQ(where_rejected(with_image(R"("warp": {"features": [{"source": [1, "2"], "target": [3, 4]}]})")),
            "$.warp.features[0].source[1]");
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "output": {"width": 0})")), "$.output.width");
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "output": {"width": 1.5})")), "$.output.width");
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "output": {"file_format": "gif"})")), "$.output.file_format");
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "output": {"border": "wrap"})")), "$.output.border");
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "output": {"depth": 8})")), "$.output.depth");
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "options": {"device": "gpu"})")), "$.options.device");
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "options": {"exact": "yes"})")), "$.options.exact");
  EXPECT_EQ(where_rejected(with_image(warp + R"(, "options": {"tolerance_px": 0})")), "$.options.tolerance_px");
  EXPECT_EQ(where_rejected(with_image(R"("mesh": {"source": {"blob": ")" + kBlob + R"("}, "features": {}})")),
            "$.mesh.source.format");
  EXPECT_EQ(where_rejected(with_image(R"("mesh": {"source": {"path": "/m.ply"}, "features": {}})")),
            "$.mesh.source.path");
  EXPECT_EQ(where_rejected(with_image(R"("mesh": {"source": {"obj": "v 0 0 0", "format": "obj"}, "features": {}})")),
            "$.mesh.source.format");
  EXPECT_EQ(where_rejected(with_image(R"("mesh": {"source": {"obj": "v"}, "features": [], "margin_px": 1})")),
            "$.mesh.features");
  EXPECT_EQ(
      where_rejected(with_image(R"("mesh": {"source": {"obj": "v"}, "features": {"features": []}, "margin_px": -1})")),
      "$.mesh.margin_px");
}

TEST(JobSpecCodec, BlobIds) {
  EXPECT_TRUE(is_blob_id(kBlob));
  EXPECT_FALSE(is_blob_id("sha256:" + std::string(63, 'a')));
  EXPECT_FALSE(is_blob_id("sha256:" + std::string(64, 'A')));
  EXPECT_FALSE(is_blob_id("md5:" + std::string(64, 'a')));
}

TEST(StatusCodec, RoundTripsAndLinksTheResultOnceSucceeded) {
  JobStatus s;
  s.id = "job_abcdefghijklmnopqrstuvwxyz";
  s.name = "n";
  s.kind = JobKind::kMesh;
  s.state = JobState::kFailed;
  s.progress = 42;
  s.attempts = 2;
  s.created_at = "2024-01-02T03:04:05.006Z";
  s.started_at = "2024-01-02T03:04:06.000Z";
  s.error = ProblemDetails{"urn:texwarp:problem:invalid-job", "Invalid job", 0, "bad", "", "$.mesh"};
  const nlohmann::json j = encode_job_status(s);
  EXPECT_TRUE(j["finished_at"].is_null());
  EXPECT_FALSE(j["links"].contains("result"));
  const JobStatus back = decode_job_status(j);
  EXPECT_EQ(encode_job_status(back), j);
  EXPECT_EQ(back.error->path, "$.mesh");
  s.state = JobState::kSucceeded;
  s.error.reset();
  EXPECT_EQ(encode_job_status(s)["links"]["result"], "/v1/jobs/" + s.id + "/result");
  EXPECT_THROW(decode_job_status(nlohmann::json{{"id", "x"}, {"kind", "image"}, {"state", "done"}}), InputError);
  JobPage page;
  page.jobs = {s, back};
  page.next_cursor = "17";
  EXPECT_EQ(encode_job_page(decode_job_page(encode_job_page(page))), encode_job_page(page));
}

TEST(ResultCodec, RoundTrips) {
  JobResult r;
  r.job_id = "job_x";
  r.kind = JobKind::kImage;
  r.files.push_back({"warped.png", "image/png", 123, std::string(64, 'b'), "/v1/jobs/job_x/files/warped.png"});
  r.report_json = R"({"kind":"image","residuals":{"max_px":0.001}})";
  const nlohmann::json j = encode_job_result(r);
  EXPECT_EQ(encode_job_result(decode_job_result(j)), j);
  EXPECT_EQ(decode_job_result(j).files[0].bytes, 123u);
  const BlobInfo b{kBlob, 10, true};
  EXPECT_EQ(decode_blob_info(encode_blob_info(b)).id, kBlob);
  EXPECT_EQ(decode_blob_info(encode_blob_info(b)).bytes, 10u);
}

}  // namespace
}  // namespace texwarp::proto
