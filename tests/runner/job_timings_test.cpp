// A job's latency budget (issue 15): every report's timings.stages names stages of the one list, which fit in the
// job's total; a job whose field is zero takes the closed form on the CPU and opens no OpenCL device; the job's PNG
// level changes the file and not the pixels; the calls run again in double are counted.
#include <gtest/gtest.h>

#include <filesystem>

#include <unistd.h>

#include "scratch_resolver.hpp"
#include "test_folder.hpp"
#include "test_jobs.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/sampler.hpp"
#include "texwarp/kernels/opencl_backend.hpp"
#include "texwarp/proto/base64.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/runner/job_runner.hpp"

namespace texwarp::runner {
namespace {

namespace fs = std::filesystem;
using proto::LatencyStage;

class JobTimingsTest : public ::testing::Test {
 protected:
  JobOutput run(const nlohmann::json& job, BackendCache& backends, const std::string& out = "out") {
    fs::create_directories(dir_ / out);
    spec_ = proto::decode_job_spec(job);
    texwarp::testing::ScratchResolver inputs(dir_.path());
    return run_job(spec_, inputs, backends, dir_ / out, {}, {});
  }

  texwarp::testing::TestFolder dir_{"timings"};
  proto::JobSpec spec_;
};

void expect_consistent(const proto::TimingsReport& t) {
  EXPECT_FALSE(t.stages[LatencyStage::kStartup]);  // a job runs in a process started before it
  for (const auto& s : t.stages.seconds) {
    if (s) {
      EXPECT_GE(*s, 0.0);
    }
  }
  EXPECT_LE(t.stages.sum(), t.total_s + 1e-9);
  // The stages as the report's JSON carries them, names from the one list.
  proto::JobReport report;
  report.image.emplace();
  report.timings = t;
  const nlohmann::json stages = proto::encode_job_report(report)["timings"]["stages"];
  for (const auto& [name, seconds] : stages.items()) {
    EXPECT_TRUE(proto::enum_from_name<LatencyStage>(name)) << name;
  }
}

TEST_F(JobTimingsTest, AnImageJobReportsEveryStageItRan) {
  BackendCache backends{proto::DeviceSpec::cpu()};
  const JobOutput out = run(texwarp::testing::image_job(48), backends);
  const proto::TimingsReport& t = out.report.timings;
  expect_consistent(t);
  for (const LatencyStage s :
       {LatencyStage::kPlan, LatencyStage::kDeviceSetup, LatencyStage::kDecode, LatencyStage::kPathlines,
        LatencyStage::kSampling, LatencyStage::kVerify, LatencyStage::kEncode, LatencyStage::kWrite}) {
    EXPECT_TRUE(t.stages[s]) << proto::to_string(s);
  }
  EXPECT_FALSE(t.stages[LatencyStage::kMapping]);
  EXPECT_EQ(out.report.method, proto::WarpMethodReport::kCertifiedLattice);
  // Decoded back from report.json: the same stages.
  EXPECT_EQ(proto::decode_job_report(proto::encode_job_report(out.report)).timings.stages, t.stages);
}

TEST_F(JobTimingsTest, AMeshJobReportsItsMapping) {
  BackendCache backends{proto::DeviceSpec::cpu()};
  const JobOutput out = run(texwarp::testing::mesh_job(), backends);
  expect_consistent(out.report.timings);
  EXPECT_TRUE(out.report.timings.stages[LatencyStage::kMapping]);
  EXPECT_TRUE(out.report.timings.stages[LatencyStage::kWrite]);
}

TEST_F(JobTimingsTest, AZeroFieldTakesTheClosedFormWithoutOpeningADevice) {
  // The default device is OpenCL; a job without features, and one whose features all sit where the similarity
  // puts them, never open it.
  BackendCache backends{proto::DeviceSpec::opencl()};
  const std::size_t contexts = opencl_activity().contexts;
  nlohmann::json identity = texwarp::testing::image_job(48);
  identity["warp"]["features"] = nlohmann::json::array();
  nlohmann::json similarity = texwarp::testing::image_job();
  similarity["warp"]["features"] = nlohmann::json::parse(R"([
    {"source": [8, 8], "target": [26, 12]}, {"source": [24, 8], "target": [58, 12]},
    {"source": [8, 24], "target": [26, 44]}, {"source": [24, 24], "target": [58, 44]}])");  // z ↦ 2·z + (10 − 4i)
  similarity["output"] = {{"width", 128}, {"height", 128}, {"border", "clamp"}};
  for (const auto& [job, name] : {std::pair{identity, "identity"}, std::pair{similarity, "similarity"}}) {
    const JobOutput out = run(job, backends, name);
    EXPECT_EQ(out.report.method, proto::WarpMethodReport::kClosedForm) << name;
    EXPECT_EQ(out.report.backend, "cpu") << name;
    ASSERT_TRUE(out.report.certificate) << name;
    EXPECT_TRUE(out.report.certificate->exact);
    EXPECT_EQ(out.report.certificate->pathlines, 0u);
    EXPECT_EQ(out.report.certificate->max_error_px_sampled, 0.0);
    EXPECT_FALSE(out.report.timings.stages[LatencyStage::kDeviceSetup]) << name;
    expect_consistent(out.report.timings);
    ASSERT_TRUE(out.report.image);
    EXPECT_LT(out.report.image->residuals.max_px, 1e-9) << name;
  }
  EXPECT_EQ(opencl_activity().contexts, contexts);
  // The similarity's output pixel (x, y) shows the source sampled at S⁻¹(x + 0.5, y + 0.5) = ((x + 0.5 − 10) / 2,
  // (y + 0.5 + 4) / 2).
  const Image source = read_image((dir_ / "texture").string());
  const Image warped = read_image((dir_ / "similarity" / "warped.png").string());
  ASSERT_EQ(warped.channels, source.channels);
  std::vector<float> expected(source.channels);
  for (const auto& [x, y] : {std::pair{39, 19}, std::pair{61, 41}, std::pair{99, 81}, std::pair{20, 100}}) {
    sample_image(source, Point((x + 0.5 - 10) / 2, (y + 0.5 + 4) / 2), Interpolation::kBilinear, Border::kClamp,
                 expected.data());
    for (int c = 0; c < source.channels; ++c) {
      EXPECT_NEAR(warped.pixels[(static_cast<std::size_t>(y) * warped.width + x) * warped.channels + c], expected[c],
                  0.51 / 255)
          << x << "," << y;
    }
  }
}

// Twelve pins whose straight paths pass 0.73 px apart (the pinned-unwrap benchmark's case 33; the OpenCL runtime test
// holds the retry to the CPU reference): on OpenCL under the automatic precision float32's steps collapse there, and
// the report counts the calls run again in double; the CPU backend, in double throughout, none.
TEST_F(JobTimingsTest, AReportCountsTheCallsRunAgainInDouble) {
  nlohmann::json job = texwarp::testing::image_job(512);
  job["image"] = {{"base64", proto::base64_encode(texwarp::testing::test_png(512))}};
  job["warp"]["features"] = nlohmann::json::parse(R"([
    {"source": [461.661, 328.41], "target": [297.333, 119.537]}, {"source": [354.452, 258.226], "target": [380.0, 153.653]},
    {"source": [351.476, 359.034], "target": [256.0, 153.653]}, {"source": [292.167, 5.12], "target": [35.556, 204.826]},
    {"source": [268.017, 188.312], "target": [214.667, 221.884]}, {"source": [239.655, 293.057], "target": [435.111, 256.0]},
    {"source": [261.455, 401.021], "target": [311.111, 256.0]}, {"source": [158.524, 450.475], "target": [448.889, 358.347]},
    {"source": [140.924, 87.109], "target": [159.556, 375.405]}, {"source": [143.669, 157.826], "target": [35.556, 375.405]},
    {"source": [138.272, 250.715], "target": [393.778, 392.463]}, {"source": [138.96, 359.414], "target": [269.778, 392.463]}])");
  BackendCache opencl{proto::DeviceSpec::opencl()};
  const JobOutput on_opencl = run(job, opencl, "opencl");
  ASSERT_TRUE(on_opencl.report.double_retries);
  EXPECT_GE(*on_opencl.report.double_retries, 1u);
  EXPECT_EQ(proto::decode_job_report(proto::encode_job_report(on_opencl.report)).double_retries,
            on_opencl.report.double_retries);
  BackendCache cpu{proto::DeviceSpec::cpu()};
  const JobOutput on_cpu = run(job, cpu, "cpu");
  EXPECT_EQ(on_cpu.report.double_retries, 0u);
  // The next job on the same OpenCL backend counts its own calls only.
  const JobOutput again = run(texwarp::testing::image_job(48), opencl, "again");
  EXPECT_EQ(again.report.double_retries, 0u);
}

TEST_F(JobTimingsTest, ThePngLevelChangesTheFileNotThePixels) {
  BackendCache backends{proto::DeviceSpec::cpu()};
  std::uintmax_t sizes[2];
  std::vector<float> pixels[2];
  for (const int i : {0, 1}) {
    nlohmann::json job = texwarp::testing::image_job(96);
    job["output"]["png_compression_level"] = i == 0 ? 0 : 9;
    const std::string out = "level" + std::to_string(i);
    run(job, backends, out);
    sizes[i] = fs::file_size(dir_ / out / "warped.png");
    pixels[i] = read_image((dir_ / out / "warped.png").string()).pixels;
  }
  EXPECT_GT(sizes[0], sizes[1]);
  EXPECT_EQ(pixels[0], pixels[1]);
  nlohmann::json bad = texwarp::testing::image_job();
  bad["output"]["png_compression_level"] = 10;
  try {
    proto::decode_job_spec(bad);
    ADD_FAILURE() << "a PNG level of 10 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("$.output.png_compression_level"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace texwarp::runner
