// The job runner (runner/): planning refuses a job's faults on submission and on the run alike, at the same JSON
// path and before any file is written; real image and mesh jobs produce report.json as the typed report encodes it,
// which decodes back to the same typed report.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "scratch_resolver.hpp"
#include "test_jobs.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/runner/job_runner.hpp"

namespace texwarp::runner {
namespace {

using texwarp::testing::ScratchResolver;

namespace fs = std::filesystem;

class JobRunnerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("texwarp-runner-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "out");
  }
  void TearDown() override { fs::remove_all(dir_); }

  JobOutput run(const nlohmann::json& job, const JobLimits& limits = {}) {
    spec_ = proto::decode_job_spec(job);
    ScratchResolver inputs(dir_);
    return run_job(spec_, inputs, backends_, dir_ / "out", limits, {});
  }

  // Where validate_job and run_job refuse `job` (they must agree), and that the run wrote nothing.
  std::string refusal(const nlohmann::json& job, const JobLimits& limits) {
    const proto::JobSpec spec = proto::decode_job_spec(job);
    ScratchResolver inputs(dir_);
    std::string on_submission = "(accepted)";
    std::string on_run = "(accepted)";
    try {
      validate_job(spec, inputs, limits);
    } catch (const InputError& e) {
      on_submission = e.what();
    }
    try {
      run_job(spec, inputs, backends_, dir_ / "out", limits, {});
    } catch (const InputError& e) {
      on_run = e.what();
    }
    EXPECT_EQ(on_submission, on_run);
    EXPECT_TRUE(fs::is_empty(dir_ / "out"));
    return on_run;
  }

  nlohmann::json report_file() const {
    std::ifstream in(dir_ / "out" / kReportFile);
    std::stringstream text;
    text << in.rdbuf();
    return nlohmann::json::parse(text.str());
  }

  // report.json is the typed report's encoding, and it decodes back to the same typed report.
  void expect_report_round_trips(const JobOutput& out) {
    const nlohmann::json file = report_file();
    EXPECT_EQ(file, nlohmann::json::parse(proto::encode_job_report(out.report).dump()));
    EXPECT_EQ(proto::decode_job_report(file), out.report);
    EXPECT_EQ(proto::encode_job_report(proto::decode_job_report(file)), file);
  }

  static std::vector<std::string> names(const JobOutput& out) {
    std::vector<std::string> n;
    for (const auto& f : out.files) n.push_back(f.name);
    return n;
  }

  fs::path dir_;
  proto::JobSpec spec_;
  BackendCache backends_{proto::DeviceSpec::cpu()};
};

TEST_F(JobRunnerTest, ImageJobReportIsTypedAndWrittenAsEncoded) {
  nlohmann::json job = testing::image_job(80);
  job["options"] = {{"jacobian_check", true}};
  const JobOutput out = run(job);
  expect_report_round_trips(out);
  EXPECT_EQ(names(out), (std::vector<std::string>{"warped.png", "report.json"}));
  EXPECT_EQ(out.report.files, names(out));
  EXPECT_EQ(out.report.kind(), proto::JobKind::kImage);
  EXPECT_EQ(out.report.backend, "cpu");
  EXPECT_EQ(out.report.method, proto::WarpMethodReport::kCertifiedLattice);
  ASSERT_TRUE(out.report.certificate && out.report.image);
  EXPECT_GT(out.report.certificate->min_jacobian_det, 0.0);
  const proto::ImageJobReport& image = *out.report.image;
  EXPECT_EQ(image.input.width, 64);
  EXPECT_EQ(image.output.width, 80);
  EXPECT_EQ(image.output.file, "warped.png");
  EXPECT_EQ(image.warp.features, 4u);
  EXPECT_EQ(image.warp.gradient_features, 1u);
  ASSERT_EQ(image.residuals.per_feature.size(), 4u);
  EXPECT_EQ(image.residuals.per_feature[3].id, "g");
  EXPECT_LT(image.residuals.max_px, 0.01);
  ASSERT_TRUE(image.jacobian);
  EXPECT_EQ(image.jacobian->step_px, 2);          // ⌈80 / 64⌉
  EXPECT_EQ(image.jacobian->samples, 40u * 40u);  // every second pixel centre of 80²
  EXPECT_EQ(image.jacobian->nonpositive, 0u);
  ASSERT_TRUE(image.closest_approach);
  EXPECT_GT(image.closest_approach->distance_px, 0.5);
  EXPECT_TRUE(out.report.timings.prepare_s && out.report.timings.read_s && out.report.timings.jacobian_s);
  EXPECT_FALSE(out.report.timings.mesh_s);
  EXPECT_GE(out.report.timings.total_s, *out.report.timings.warp_s);
}

TEST_F(JobRunnerTest, MeshJobReportIsTypedAndWrittenAsEncoded) {
  nlohmann::json job = testing::mesh_job();
  job["mesh"]["per_triangle"] = true;
  job["mesh"]["per_vertex"] = true;
  const JobOutput out = run(job);
  expect_report_round_trips(out);
  EXPECT_EQ(names(out), (std::vector<std::string>{"mesh.obj", "uvs.json", "warped.png", "report.json"}));
  EXPECT_EQ(out.report.kind(), proto::JobKind::kMesh);
  ASSERT_TRUE(out.report.certificate && out.report.mesh);
  const proto::MeshMappingReport& mesh = *out.report.mesh;
  EXPECT_EQ(mesh.mesh.faces, 72);
  EXPECT_EQ(mesh.region.vertices, 49);
  EXPECT_EQ(mesh.region.boundary_vertices, 24u);
  EXPECT_EQ(mesh.features.size(), 5u);
  EXPECT_EQ(mesh.features[4].id, "p33");
  ASSERT_TRUE(mesh.triangles && mesh.vertices);
  EXPECT_EQ(mesh.triangles->size(), 72u);
  EXPECT_EQ(mesh.vertices->size(), 49u);
  EXPECT_EQ(mesh.uvs.flipped_triangles, 0);
  EXPECT_LT(mesh.max_residual_px, 1.0);
  EXPECT_TRUE(out.report.timings.mesh_s && out.report.timings.mapping_s && out.report.timings.warp_s);
  EXPECT_FALSE(out.report.timings.prepare_s);
}

TEST_F(JobRunnerTest, MeshJobWithoutImageHasNoCertificate) {
  nlohmann::json job = testing::mesh_job();
  job["output"] = {{"image", false}};
  const JobOutput out = run(job);
  expect_report_round_trips(out);
  EXPECT_EQ(names(out), (std::vector<std::string>{"mesh.obj", "uvs.json", "report.json"}));
  EXPECT_EQ(out.report.method, proto::WarpMethodReport::kNone);
  EXPECT_FALSE(out.report.certificate);
  EXPECT_TRUE(report_file().at("certificate").is_null());
  EXPECT_FALSE(out.report.timings.warp_s);
}

TEST_F(JobRunnerTest, SubmissionAndRunRefuseTheSameFaultsBeforeWritingAnything) {
  JobLimits few_features;
  few_features.max_features = 3;
  EXPECT_EQ(refusal(testing::image_job(), few_features), "$.warp.features: 4 features, more than the limit of 3");
  EXPECT_EQ(refusal(testing::mesh_job(), few_features),
            "$.mesh.features.features: 5 features, more than the limit of 3");

  JobLimits small_output;
  small_output.max_output_pixels = 100 * 100;
  EXPECT_EQ(refusal(testing::image_job(101), small_output).rfind("$.output: the warped image would have 101×101", 0),
            0u);

  JobLimits tiny_memory;
  tiny_memory.max_job_memory_bytes = 1000;
  EXPECT_EQ(refusal(testing::image_job(), tiny_memory).rfind("$.image: ", 0), 0u);
  EXPECT_EQ(refusal(testing::mesh_job(), tiny_memory).rfind("$.mesh.source: ", 0), 0u);

  nlohmann::json no_image = testing::image_job();
  no_image["output"] = {{"image", false}};
  EXPECT_EQ(refusal(no_image, {}).rfind("$.output.image: ", 0), 0u);

  nlohmann::json duplicate = testing::image_job();
  duplicate["warp"]["features"][1]["source"] = duplicate["warp"]["features"][0]["source"];
  const std::string twice = refusal(duplicate, {});
  EXPECT_EQ(twice.rfind("$.warp.features[1]", 0), 0u) << twice;
  EXPECT_NE(twice.find("duplicate source position (16, 16)"), std::string::npos) << twice;

  nlohmann::json bad_region = testing::mesh_job();
  bad_region["mesh"]["region"] = {{"faces", "all"}};
  // The region is decoded with the job spec (proto's typed region), so the job is refused before it is planned.
  std::string region = "(accepted)";
  try {
    proto::decode_job_spec(bad_region);
  } catch (const InputError& e) {
    region = e.what();
  }
  EXPECT_EQ(region.rfind("$.mesh.region.faces: ", 0), 0u) << region;
}

}  // namespace
}  // namespace texwarp::runner
