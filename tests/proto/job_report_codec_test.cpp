// The typed report's codec (proto/job_report_codec.hpp) against itself and against report.schema.json: every
// report round-trips (typed → JSON → typed, JSON → typed → JSON), each schema object lists exactly the keys the
// encoder writes and requires exactly the keys the decoder requires (at the same JSON path), and numbers that are
// not finite travel as null.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <set>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_report_codec.hpp"

namespace texwarp::proto {
namespace {

nlohmann::json schema() {
  std::ifstream in(std::filesystem::path(TEXWARP_SOURCE_DIR) / "proto" / "schema" / "report.schema.json");
  return nlohmann::json::parse(in);
}

std::set<std::string> keys(const nlohmann::json& object) {
  std::set<std::string> out;
  for (const auto& [k, v] : object.items()) out.insert(k);
  return out;
}

// A $defs entry's properties, with those of the definitions it composes (allOf).
std::set<std::string> schema_keys(const nlohmann::json& defs, const std::string& name) {
  const nlohmann::json& def = defs.at(name);
  std::set<std::string> out = def.contains("properties") ? keys(def["properties"]) : std::set<std::string>{};
  for (const auto& part : def.value("allOf", nlohmann::json::array())) {
    const std::string ref = part.at("$ref");
    for (const auto& k : schema_keys(defs, ref.substr(ref.rfind('/') + 1))) out.insert(k);
  }
  return out;
}

std::set<std::string> schema_required(const nlohmann::json& defs, const std::string& name) {
  const nlohmann::json& def = defs.at(name);
  std::set<std::string> out;
  for (const auto& k : def.value("required", nlohmann::json::array())) out.insert(k);
  for (const auto& part : def.value("allOf", nlohmann::json::array())) {
    const std::string ref = part.at("$ref");
    for (const auto& k : schema_required(defs, ref.substr(ref.rfind('/') + 1))) out.insert(k);
  }
  return out;
}

TrajectoryReport trajectory() { return {3, TrajectoryMethod::kSweep, 2.5, {0.0, 0.25, 0.75, 1.0}, std::nullopt}; }
CertificateReport certificate() {
  return {false, 0.05, 0.01, 0.02, 0.045, 1024, 0.7, 0, 5000, 900, 64, 300, 8, trajectory()};
}
WarpSetupReport warp_setup() { return {2.0, Prealign::kNone, 0.01, 4, 1, 0.25}; }
ResidualsReport residuals() { return {1e-7, {{"features[0] (\"a\")", "a", 1e-7}, {"features[1]", "", 0.0}}}; }
JacobianReport jacobian() {
  return {JacobianEstimate::kCentralDifferences,
          std::array<int, 2>{100, 90},
          std::array<int, 2>{50, 45},
          2,
          2250,
          0.5,
          1.5,
          0};
}
TimingsReport timings() { return {0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 4.0, {}}; }

JobReport image_job_report() {
  JobReport r;
  r.backend = "opencl:pocl";
  r.double_retries = 2;
  r.method = WarpMethodReport::kPerPixel;
  r.exact = true;
  r.certificate = certificate();
  ImageJobReport& i = r.image.emplace();
  i.input = {64, 48, 3, PixelFormat::kUint8};
  i.output = {"warped.exr",
              80,
              60,
              4,
              PixelFormat::kHalf,
              Interpolation::kBicubic,
              Border::kTransparent,
              SamplingReport{ImageRole::kColor, "sRGB", std::nullopt, SamplingFilter::kFootprint, 1234, 2, 0}};
  i.warp = warp_setup();
  i.prealignment = {1.1, -30.0, {2.5, -1.0}};
  i.closest_approach = ClosestApproachReport{{"features[0] (\"a\")", "features[2]"}, 0.5, 3.25};
  i.trajectory = trajectory();
  i.residuals = residuals();
  i.jacobian = jacobian();
  i.mirror = MirrorReport{true, 0.05, false, std::string("add \"mirror\": true")};
  i.maps = std::vector<MapReport>{{"base", i.input, i.output, 0.5, 0.25, 0.125}};
  r.timings = timings();
  r.files = {"warped.exr", "report.json"};
  return r;
}

MeshMappingReport mesh_mapping() {
  MeshMappingReport m;
  m.uv_origin = UvOrigin::kTopLeft;
  m.mesh = {49, 36, 72};
  m.region = {30, 49, 24, 60};
  m.texture = {64, 64};
  m.warped_texture = {70, 70};
  m.lscm = {{0, 48}, 1e-3, 9.5, 0.01};
  m.warp = warp_setup();
  m.trajectory = TrajectoryReport{
      1, TrajectoryMethod::kStraight, std::nullopt, {0.0, 1.0}, std::nullopt, std::nullopt, std::nullopt};
  m.uvs = {1.02, 1.3, 0.04, 0, 1, 2.5};
  m.max_residual_px = 0.3;
  m.mean_residual_px = 0.1;
  m.vertices_outside_texture = 2;
  m.warped_uvs = {1.0, 1.0, 0.0, 0, 0, 1.0};
  m.seconds = 1.5;
  m.features = {
      {0, "p11", 3, {0.2, 0.3, 0.5}, {1.0, 2.0, 0.0}, {12.0, 50.0}, {10.0, 11.0}, true, 0.25, 0.01},
      {1, std::nullopt, 4, {1.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {1.0, 2.0}, {3.0, 4.0}, false, 0.0, std::nullopt}};
  m.triangles = std::vector<TriangleReport>{{0, 1.0, 1.1, 0.01, false, false, 0}, {72, 2.0, 2.5, 0.2, true, false, 0}};
  m.vertices = std::vector<VertexReport>{
      {7, {0.1, 0.9}, {0.2, 0.8}, std::nullopt},
      {49, {0.3, 0.4}, {0.5, 0.6}, SourcePointReport{0, {0.5, 0.5, 0.0}, std::array<int, 3>{3, 4, 11}}}};
  m.embedding = EmbeddingReport{EmbeddingMethod::kMeanValue, {5, 6}};
  m.flips = std::vector<FlippedFaceReport>{{72, 0, FlipCause::kWarp}, {3, std::nullopt, FlipCause::kEmbedding}};
  m.refinement = RefinementReport{1, 2, 3, 4, 5, 53, 77, 9, 0, 784, RefinementStop::kFlipFree, true, 0.25};
  m.untangling = UvUntanglingReport{true, 12, 0, 7, 0.125};
  m.optimization = UvOptimizationReport{
      UvOptimize::kStretch,        false, std::string("3 UV triangles still flip"), 0, false, 4.5, 4.5,
      {1.1, 1.5, 0.05, 3, 0, 3.0}, 0.01};
  m.texture_sampling =
      SamplingReport{ImageRole::kNormal, std::nullopt, NormalConvention::kDirectX, SamplingFilter::kPoint, 0, 0, 3};
  OutputImageReport normal{"normal.png",      96, 80, 3, PixelFormat::kUint16, Interpolation::kBicubic, Border::kClamp,
                           m.texture_sampling};
  m.maps = std::vector<MapReport>{{"normal", {64, 64, 3, PixelFormat::kUint16}, normal, 0.5, 0.25, 0.125}};
  return m;
}

JobReport mesh_job_report() {
  JobReport r;
  r.backend = "cpu";
  r.double_retries = 0;
  r.method = WarpMethodReport::kNone;
  r.mesh = mesh_mapping();
  r.timings = timings();
  r.files = {"mesh.obj", "uvs.json", "report.json"};
  return r;
}

CheckReport check_report() {
  CheckReport r;
  r.features = {4, 3, 1};
  r.options = {2.0, Prealign::kSimilarity, 0.01, 0.5};
  r.prealignment = {1.0, 0.0, {0.0, 0.0}};
  r.closest_approach = ClosestApproachReport{{"features[0]", "features[1]"}, 0.0, 40.0};
  r.trajectory = TrajectoryReport{2,
                                  TrajectoryMethod::kRepaired,
                                  0.75,
                                  {0.0, 0.5, 1.0},
                                  40.0,
                                  21.5,
                                  {{{{0.0, 1.0}, {2.0, 3.0}}, {{0.5, 1.5}, {2.5, 3.5}}, {{1.0, 2.0}, {3.0, 4.0}}}}};
  r.distortion = DistortionReport{1.8, 1.1, 0.4};
  r.residuals = {1e-8, {{"features[0]", std::nullopt, 1e-8}}};
  r.gradient_features = {{"features[3] (\"g\")", 1.2, 1.2000001, 15.0, 1e-5}};
  r.jacobian = jacobian();
  r.method = "tps";
  r.backend = "cpu";
  return r;
}

TEST(JobReportCodec, EveryReportRoundTrips) {
  for (const JobReport& r : {image_job_report(), mesh_job_report()}) {
    const nlohmann::json j = encode_job_report(r);
    EXPECT_EQ(decode_job_report(j), r);
    EXPECT_EQ(encode_job_report(decode_job_report(nlohmann::json::parse(j.dump()))), j);
  }
  const CheckReport check = check_report();
  EXPECT_EQ(decode_check_report(encode_check_report(check)), check);
  CheckReport refused;
  refused.failure = CheckFailureReport{"$.features[1]", "duplicate source position (1, 2)"};
  EXPECT_EQ(
      encode_check_report(refused),
      nlohmann::json({{"valid", false}, {"where", "$.features[1]"}, {"error", "duplicate source position (1, 2)"}}));
  EXPECT_EQ(decode_check_report(encode_check_report(refused)), refused);
  EXPECT_EQ(decode_mesh_mapping_report(encode_mesh_mapping_report(mesh_mapping())), mesh_mapping());
  EXPECT_EQ(decode_certificate_report(encode_certificate_report(certificate())), certificate());
}

TEST(JobReportCodec, TheJsonHasTheReportFilesShape) {
  const nlohmann::json image = encode_job_report(image_job_report());
  EXPECT_EQ(image["kind"], "image");
  EXPECT_EQ(image["method"], "per_pixel");
  EXPECT_EQ(image["warp"]["prealign"], "none");
  EXPECT_EQ(image["residuals"]["per_feature"][1],
            nlohmann::json({{"feature", "features[1]"}, {"id", ""}, {"residual_px", 0.0}}));
  EXPECT_EQ(image["jacobian"]["map"], "inverse (output pixel → source pixel), central differences at pixel centres");
  JobReport bare = image_job_report();
  bare.image->closest_approach.reset();
  bare.image->jacobian.reset();
  EXPECT_TRUE(encode_job_report(bare)["closest_approach"].is_null());
  EXPECT_TRUE(encode_job_report(bare)["jacobian"].is_null());
  // A mesh job: the mapping's fields at the top level, the quality of the UVs into the texture flat among them.
  const nlohmann::json mesh = encode_job_report(mesh_job_report());
  EXPECT_EQ(mesh["kind"], "mesh");
  EXPECT_TRUE(mesh["certificate"].is_null());
  EXPECT_EQ(mesh["l2_stretch"], 1.02);
  EXPECT_EQ(mesh["degenerate_triangles"], 1);
  EXPECT_EQ(mesh["warped_uvs"]["l2_stretch"], 1.0);
  EXPECT_FALSE(mesh["features"][1].contains("id"));
  EXPECT_FALSE(mesh["features"][1].contains("snap_distance"));
  EXPECT_EQ(mesh["timings"]["total_s"], 4.0);
}

TEST(JobReportCodec, NumbersThatAreNotFiniteTravelAsNull) {
  JobReport r = image_job_report();
  r.certificate->min_jacobian_det = std::numeric_limits<double>::quiet_NaN();
  r.image->jacobian->min_det = std::numeric_limits<double>::infinity();
  const nlohmann::json j = encode_job_report(r);
  EXPECT_TRUE(j["certificate"]["min_jacobian_det"].is_null());
  EXPECT_TRUE(j["jacobian"]["min_det"].is_null());
  const JobReport back = decode_job_report(j);
  EXPECT_TRUE(std::isnan(back.certificate->min_jacobian_det));
  EXPECT_TRUE(std::isnan(back.image->jacobian->min_det));
}

TEST(JobReportCodec, SchemaObjectsListExactlyTheKeysTheEncoderWrites) {
  const nlohmann::json defs = schema().at("$defs");
  const nlohmann::json image = encode_job_report(image_job_report());
  const nlohmann::json mesh = encode_job_report(mesh_job_report());
  const nlohmann::json check = encode_check_report(check_report());
  EXPECT_EQ(schema_keys(defs, "imageJobReport"), keys(image));
  EXPECT_EQ(schema_keys(defs, "meshJobReport"), keys(mesh));
  EXPECT_EQ(schema_keys(defs, "meshMappingReport"), keys(encode_mesh_mapping_report(mesh_mapping())));
  EXPECT_EQ(keys(defs["checkReport"]["oneOf"][1]["properties"]), keys(check));
  EXPECT_EQ(keys(defs["checkReport"]["oneOf"][0]["properties"]), (std::set<std::string>{"valid", "where", "error"}));
  const std::vector<std::pair<std::string, nlohmann::json>> sections = {
      {"certificate", image["certificate"]},    {"warpSetup", image["warp"]},
      {"prealignment", image["prealignment"]},  {"closestApproach", image["closest_approach"]},
      {"residuals", image["residuals"]},        {"featureResidual", image["residuals"]["per_feature"][0]},
      {"jacobian", image["jacobian"]},          {"inputImage", image["input"]},
      {"outputImage", image["output"]},         {"timings", image["timings"]},
      {"imageSize", mesh["texture"]},           {"uvQuality", mesh["warped_uvs"]},
      {"placedFeature", mesh["features"][0]},   {"triangle", mesh["triangles"][0]},
      {"vertex", mesh["vertices"][1]},          {"gradientCheck", check["gradient_features"][0]},
      {"embedding", mesh["embedding"]},         {"flippedFace", mesh["flips"][0]},
      {"refinement", mesh["refinement"]},       {"sourcePoint", mesh["vertices"][1]["source"]},
      {"trajectory", check["trajectory"]},      {"distortion", check["distortion"]},
      {"uvOptimization", mesh["optimization"]}, {"mapReport", image["maps"][0]}};
  for (const auto& [name, value] : sections) EXPECT_EQ(schema_keys(defs, name), keys(value)) << name;
}

// Where the decoder refuses `doc`, or "(accepted)".
std::string refusal(const std::function<void()>& decode) {
  try {
    decode();
  } catch (const InputError& e) {
    return e.where().str();
  }
  return "(accepted)";
}

TEST(JobReportCodec, RequiredKeysAgreeWithTheSchema) {
  const nlohmann::json defs = schema().at("$defs");
  struct Case {
    std::string def;
    nlohmann::json doc;
    nlohmann::json::json_pointer object;
    std::string path;
    std::function<void(const nlohmann::json&)> decode;
  };
  const auto job = [](const nlohmann::json& j) { decode_job_report(j); };
  const nlohmann::json image = encode_job_report(image_job_report());
  const nlohmann::json mesh = encode_job_report(mesh_job_report());
  const std::vector<Case> cases = {
      {"imageJobReport", image, nlohmann::json::json_pointer(""), "$", job},
      {"meshJobReport", mesh, nlohmann::json::json_pointer(""), "$", job},
      {"certificate", image, nlohmann::json::json_pointer("/certificate"), "$.certificate", job},
      {"warpSetup", image, nlohmann::json::json_pointer("/warp"), "$.warp", job},
      {"jacobian", image, nlohmann::json::json_pointer("/jacobian"), "$.jacobian", job},
      {"featureResidual", image, nlohmann::json::json_pointer("/residuals/per_feature/1"), "$.residuals.per_feature[1]",
       job},
      {"timings", image, nlohmann::json::json_pointer("/timings"), "$.timings", job},
      {"placedFeature", mesh, nlohmann::json::json_pointer("/features/0"), "$.features[0]", job},
      {"flippedFace", mesh, nlohmann::json::json_pointer("/flips/0"), "$.flips[0]", job},
      {"refinement", mesh, nlohmann::json::json_pointer("/refinement"), "$.refinement", job},
      {"embedding", mesh, nlohmann::json::json_pointer("/embedding"), "$.embedding", job},
      {"trajectory", image, nlohmann::json::json_pointer("/trajectory"), "$.trajectory", job}};
  for (const Case& c : cases) {
    const std::set<std::string> required = schema_required(defs, c.def);
    for (const auto& k : keys(c.doc[c.object])) {
      nlohmann::json without = c.doc;
      without[c.object].erase(k);
      const std::string where = refusal([&] { c.decode(without); });
      EXPECT_EQ(where, required.count(k) ? (c.path == "$" ? "$." + k : c.path + "." + k) : "(accepted)")
          << c.def << " " << k;
    }
  }
}

// The keys added after the report's first version, where each sits in a report.
const std::vector<std::pair<std::string, std::string>> kAddedKeys = {{"/certificate", "max_error_px_bound"},
                                                                     {"/certificate", "pixel_pathlines"},
                                                                     {"", "mirror"},
                                                                     {"", "embedding"},
                                                                     {"", "flips"},
                                                                     {"/mesh", "triangles"},
                                                                     {"/region", "triangles"},
                                                                     {"/vertices/1/source", "corners"},
                                                                     {"/output", "sampling"},
                                                                     {"", "texture_sampling"},
                                                                     {"", "double_retries"}};

// A report from a texwarpd before them: this version's report without one of them, or without all, decodes with
// that member unknown (std::nullopt); the schema does not require them and says why, and no other key.
TEST(JobReportCodec, AReportWithoutTheKeysAddedSinceTheFirstVersionDecodesThemAsUnknown) {
  const nlohmann::json image = encode_job_report(image_job_report());
  const nlohmann::json mesh = encode_job_report(mesh_job_report());
  nlohmann::json old_image = image, old_mesh = mesh;
  for (const auto& [object, key] : kAddedKeys) {
    const nlohmann::json::json_pointer at(object);
    const bool in_image = image.contains(at) && image.at(at).contains(key);
    const nlohmann::json& full = in_image ? image : mesh;
    nlohmann::json without = full;
    ASSERT_EQ(without.at(at).erase(key), 1u) << object << "/" << key;
    EXPECT_NE(decode_job_report(without), decode_job_report(full)) << object << "/" << key;
    EXPECT_EQ(encode_job_report(decode_job_report(without)), without) << object << "/" << key;
    (in_image ? old_image : old_mesh).at(at).erase(key);
  }
  const JobReport older_image = decode_job_report(old_image);
  EXPECT_FALSE(older_image.certificate->max_error_px_bound.has_value());
  EXPECT_FALSE(older_image.certificate->pixel_pathlines.has_value());
  EXPECT_FALSE(older_image.image->mirror.has_value());
  EXPECT_FALSE(older_image.image->output.sampling.has_value());
  EXPECT_FALSE(older_image.double_retries.has_value());
  EXPECT_EQ(older_image.certificate->max_error_px_estimated, image_job_report().certificate->max_error_px_estimated);
  const JobReport older_mesh = decode_job_report(old_mesh);
  EXPECT_FALSE(older_mesh.mesh->mesh.triangles.has_value());
  EXPECT_FALSE(older_mesh.mesh->region.triangles.has_value());
  EXPECT_FALSE(older_mesh.mesh->embedding.has_value());
  EXPECT_FALSE(older_mesh.mesh->flips.has_value());
  EXPECT_FALSE(older_mesh.mesh->texture_sampling.has_value());
  EXPECT_FALSE(older_mesh.mesh->vertices->at(1).source->corners.has_value());
  EXPECT_EQ(older_mesh.mesh->mesh.faces, 36);
  EXPECT_EQ(older_mesh.mesh->features, mesh_mapping().features);
  // Only those: a key of the first version is still required (the schema agrees: RequiredKeysAgreeWithTheSchema).
  nlohmann::json no_faces = mesh;
  no_faces["mesh"].erase("faces");
  EXPECT_EQ(refusal([&] { decode_job_report(no_faces); }), "$.mesh.faces");

  // The schema: not required, and said so in the description, for exactly these keys.
  const std::string marker = "Added after the report's first version";
  const nlohmann::json defs = schema().at("$defs");
  const nlohmann::json& mapping_props = defs.at("meshMapping").at("properties");
  const std::vector<std::pair<nlohmann::json, std::string>> objects = {{defs.at("certificate"), "max_error_px_bound"},
                                                                       {defs.at("certificate"), "pixel_pathlines"},
                                                                       {defs.at("imageJobReport"), "mirror"},
                                                                       {defs.at("meshMapping"), "embedding"},
                                                                       {defs.at("meshMapping"), "flips"},
                                                                       {mapping_props.at("mesh"), "triangles"},
                                                                       {mapping_props.at("region"), "triangles"},
                                                                       {defs.at("sourcePoint"), "corners"},
                                                                       {defs.at("outputImage"), "sampling"},
                                                                       {defs.at("meshMapping"), "texture_sampling"},
                                                                       {defs.at("jobFields"), "double_retries"}};
  ASSERT_EQ(objects.size(), kAddedKeys.size());
  for (const auto& [object, key] : objects) {
    const nlohmann::json required = object.value("required", nlohmann::json::array());
    EXPECT_EQ(std::count(required.begin(), required.end(), key), 0) << key;
    EXPECT_EQ(object.at("properties").at(key).at("description").get<std::string>().rfind(marker, 0), 0u) << key;
  }
  const std::string text = schema().dump();
  std::size_t marked = 0;
  for (std::size_t at = text.find(marker); at != std::string::npos; at = text.find(marker, at + 1)) ++marked;
  EXPECT_EQ(marked, kAddedKeys.size());
}

TEST(JobReportCodec, DecodingNamesTheOffendersPath) {
  nlohmann::json j = encode_job_report(image_job_report());
  j["residuals"]["per_feature"][1]["residual_px"] = "small";
  EXPECT_EQ(refusal([&] { decode_job_report(j); }), "$.residuals.per_feature[1].residual_px");
  j = encode_job_report(image_job_report());
  j["method"] = "approximate";
  EXPECT_EQ(refusal([&] { decode_job_report(j); }), "$.method");
  j = encode_job_report(image_job_report());
  j["prealignment"]["translation"] = {1.0};
  EXPECT_EQ(refusal([&] { decode_job_report(j); }), "$.prealignment.translation");
  j = encode_job_report(image_job_report());
  j["certificate"]["sampled_pixels"] = -1;
  EXPECT_EQ(refusal([&] { decode_job_report(j); }), "$.certificate.sampled_pixels");
  // Keys it does not know are ignored, as by every response codec.
  j = encode_job_report(image_job_report());
  j["added_later"] = 1;
  EXPECT_EQ(decode_job_report(j), image_job_report());
}

}  // namespace
}  // namespace texwarp::proto
