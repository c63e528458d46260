// The job runner (runner/): planning refuses a job's faults on submission and on the run alike, at the same JSON
// path and before any file is written; real image and mesh jobs produce report.json as the typed report encodes it,
// which decodes back to the same typed report.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include <unistd.h>

#include "mesh_test_shapes.hpp"
#include "scratch_resolver.hpp"
#include "test_folder.hpp"
#include "test_jobs.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/mesh/mesh_input.hpp"
#include "texwarp/mesh/texture_mapping.hpp"
#include "texwarp/proto/base64.hpp"
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
  void SetUp() override { fs::create_directories(dir_ / "out"); }

  JobOutput run(const nlohmann::json& job, const JobLimits& limits = {}) {
    spec_ = proto::decode_job_spec(job);
    ScratchResolver inputs(dir_.path());
    return run_job(spec_, inputs, backends_, dir_ / "out", limits, {});
  }

  // Where validate_job and run_job refuse `job` (they must agree), and that the run wrote nothing.
  std::string refusal(const nlohmann::json& job, const JobLimits& limits) {
    const proto::JobSpec spec = proto::decode_job_spec(job);
    ScratchResolver inputs(dir_.path());
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

  texwarp::testing::TestFolder dir_{"runner"};
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

// A bent 30×30 grid (1 800 faces) with 12 vertex pins, as tests/mesh/mesh_flips_test.cpp's BentGrid(31): the warp's
// UVs flip one face, the warp bending inside it (straight trajectories: no pair passes close, so the planner's
// energy lowering, which unfolds mesh_flips_test's seed 47, leaves this set as it is). Sources: where the mapping
// without pins puts the vertices, moved ±40 px.
nlohmann::json bent_grid_job(const mesh::TriangleMesh& grid) {
  const mesh::MeshRegion region = mesh::whole_mesh_region(grid, proto::InputLocation::file("grid"));
  mesh::TextureMappingOptions options;
  // A 600² texture with the 512² warped texture's picture 44 px in: pins moved ±40 px stay on it (a pin outside the
  // texture is refused); a common shift of the sources moves only the pre-alignment, not the flips.
  options.texture_width = options.texture_height = 600;
  options.frame_width = options.frame_height = 512;
  CpuBackend backend;
  const mesh::TextureMapping identity = mesh::map_texture(backend, grid, region, {}, options);
  std::mt19937 rng(31);
  std::uniform_int_distribution<int> pick(0, grid.vertex_count() - 1);
  std::uniform_real_distribution<double> offset(-40.0, 40.0);
  nlohmann::json features = nlohmann::json::array();
  for (int k = 0; k < 12; ++k) {
    const int v = pick(rng);
    const double dx = offset(rng), dy = offset(rng);
    const Point source = identity.frame.pixels[region.local_vertex[v]] + Point(44.0 + dx, 44.0 + dy);
    features.push_back({{"source", {source.real(), source.imag()}}, {"target", {{"vertex", v}}}});
  }
  nlohmann::json vertices = nlohmann::json::array(), triangles = nlohmann::json::array();
  for (const auto& p : grid.vertices) vertices.push_back({p.x, p.y, p.z});
  for (const auto& f : grid.faces) triangles.push_back({f[0], f[1], f[2]});
  return {{"image", {{"base64", proto::base64_encode(testing::test_png(600))}}},
          {"mesh",
           {{"source", {{"inline", {{"vertices", vertices}, {"triangles", triangles}}}}},
            {"features", {{"alpha", 2.0}, {"tolerance_px", 0.01}, {"features", features}}},
            {"per_triangle", true}}},
          {"output", {{"image", false}, {"width", 512}, {"height", 512}}}};
}

// Output faces whose UVs (uvs.json, v up) are clockwise, and every output face by its OBJ vertex ids.
std::vector<int> flipped_faces(const mesh::TriangleMesh& obj, const nlohmann::json& uvs) {
  std::map<int, std::array<double, 2>> uv;
  for (std::size_t i = 0; i < uvs["vertices"].size(); ++i) {
    uv[uvs["vertices"][i].get<int>()] = uvs["uv"][i].get<std::array<double, 2>>();
  }
  std::vector<int> out;
  for (int f = 0; f < obj.face_count(); ++f) {
    const auto a = uv.at(obj.faces[f][0]), b = uv.at(obj.faces[f][1]), c = uv.at(obj.faces[f][2]);
    if ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) < 0.0) out.push_back(f);
  }
  return out;
}

TEST_F(JobRunnerTest, MeshJobNamesTheFaceTheWarpFlipsAndRefineLeavesNone) {
  const mesh::TriangleMesh grid = mesh::testing::cylinder_strip(1.0, 2.0, 2.0, 30, 30);
  nlohmann::json job = bent_grid_job(grid);
  job["options"] = {{"refine", false}, {"optimize", "none"}};  // the warp's UVs on the input's faces
  const JobOutput plain = run(job);
  expect_report_round_trips(plain);
  const nlohmann::json plain_uvs = nlohmann::json::parse(read_text_file((dir_ / "out" / kUvFile).string(), 1 << 26));
  const std::vector<int> flipped = flipped_faces(mesh::read_mesh_file((dir_ / "out" / kObjFile).string()), plain_uvs);
  ASSERT_EQ(flipped.size(), 1u);
  const proto::MeshMappingReport& before = *plain.report.mesh;
  EXPECT_EQ(before.uvs.flipped_triangles, 1);
  ASSERT_TRUE(before.flips && before.embedding);
  ASSERT_EQ(before.flips->size(), 1u);
  EXPECT_EQ((*before.flips)[0].face, flipped[0]);
  EXPECT_EQ((*before.flips)[0].cause, proto::FlipCause::kWarp);
  EXPECT_EQ(before.embedding->method, proto::EmbeddingMethod::kLscm);
  EXPECT_FALSE(before.refinement);
  EXPECT_FALSE(plain_uvs.contains("source_face"));

  // The default (refined, untangled first, optimised): the one flip is untangled on the input's faces.
  fs::remove_all(dir_ / "out");
  fs::create_directories(dir_ / "out");
  job["options"] = nlohmann::json::object();
  const JobOutput untangled = run(job);
  expect_report_round_trips(untangled);
  const proto::MeshMappingReport& optimised = *untangled.report.mesh;
  ASSERT_TRUE(optimised.refinement && optimised.untangling && optimised.optimization);
  EXPECT_EQ(optimised.refinement->stop, proto::RefinementStop::kUntangled);
  EXPECT_EQ(optimised.refinement->output_faces, grid.face_count());
  EXPECT_EQ(optimised.untangling->flipped_before, 1);
  EXPECT_TRUE(optimised.untangling->applied);
  EXPECT_EQ(optimised.uvs.flipped_triangles, 0);
  EXPECT_TRUE(flipped_faces(mesh::read_mesh_file((dir_ / "out" / kObjFile).string()),
                            nlohmann::json::parse(read_text_file((dir_ / "out" / kUvFile).string(), 1 << 26)))
                  .empty());
  EXPECT_TRUE(optimised.optimization->applied);
  EXPECT_LT(optimised.uvs.l2_stretch, optimised.optimization->before.l2_stretch);
  EXPECT_FALSE(before.optimization);

  // Refined by bisection (the warp's own UVs: no untangling): the flip's faces are split until none flips.
  fs::remove_all(dir_ / "out");
  fs::create_directories(dir_ / "out");
  job["options"] = {{"optimize", "none"}};
  const JobOutput refined = run(job);
  expect_report_round_trips(refined);
  const proto::MeshMappingReport& after = *refined.report.mesh;
  ASSERT_TRUE(after.refinement);
  EXPECT_EQ(after.uvs.flipped_triangles, 0);
  ASSERT_TRUE(after.flips);
  EXPECT_TRUE(after.flips->empty());
  EXPECT_EQ(after.refinement->stop, proto::RefinementStop::kFlipFree);
  // Independently, from the files: no flipped UV triangle, and each output face lies in its source face.
  const mesh::TriangleMesh obj = mesh::read_mesh_file((dir_ / "out" / kObjFile).string());
  const nlohmann::json uvs = nlohmann::json::parse(read_text_file((dir_ / "out" / kUvFile).string(), 1 << 26));
  EXPECT_TRUE(flipped_faces(obj, uvs).empty());
  EXPECT_EQ(obj.face_count(), after.refinement->output_faces);
  EXPECT_EQ(obj.vertex_count(), after.refinement->output_vertices);
  EXPECT_GT(obj.face_count(), grid.face_count());
  const auto source_face = uvs.at("source_face").get<std::vector<int>>();
  ASSERT_EQ(static_cast<int>(source_face.size()), obj.face_count());
  for (int f = 0; f < obj.face_count(); ++f) {
    const int s = source_face[f];
    if (f < grid.face_count()) {
      EXPECT_EQ(s, f);
    }
    for (int k = 0; k < 3; ++k) {
      const mesh::ClosestPoint p =
          mesh::closest_point_on_triangle(obj.corner(f, k), grid.corner(s, 0), grid.corner(s, 1), grid.corner(s, 2));
      EXPECT_LT(p.distance, 1e-5) << "output face " << f;
    }
  }
  EXPECT_EQ(uvs.at("new_vertices").at("first"), grid.vertex_count());
  EXPECT_EQ(static_cast<int>(uvs["new_vertices"]["source"].size()), obj.vertex_count() - grid.vertex_count());
  ASSERT_TRUE(after.triangles);
  for (const proto::TriangleReport& t : *after.triangles) EXPECT_EQ(t.source_face, source_face[t.face]);
}

// Refinement's vertex bound follows the job's memory budget: what is left once the unrefined job fits (this job: an
// inline mesh of 1 800 faces, no image: 1 800 × (256 + 1 280) bytes), each new vertex counted as two faces. With
// nothing left the region keeps its 961 vertices (bisection stops at once and the flip stays); with room for
// 100 000 more, the usual 16× bound, and no flip.
TEST_F(JobRunnerTest, MeshJobRefinementIsBoundedByTheMemoryBudget) {
  const mesh::TriangleMesh grid = mesh::testing::cylinder_strip(1.0, 2.0, 2.0, 30, 30);
  nlohmann::json job = bent_grid_job(grid);
  job["options"] = {{"optimize", "none"}};  // bisection of the warp's own UVs (no untangling)
  constexpr std::uint64_t kUnrefined = 1800ull * (256 + 1280);
  JobLimits just_enough;
  just_enough.max_job_memory_bytes = kUnrefined;
  const JobOutput tight = run(job, just_enough);
  ASSERT_TRUE(tight.report.mesh->refinement);
  const auto& capped = *tight.report.mesh->refinement;
  EXPECT_EQ(capped.vertex_limit, 961);
  EXPECT_EQ(capped.stop, proto::RefinementStop::kVertexLimit);
  EXPECT_EQ(tight.report.mesh->uvs.flipped_triangles, 1);

  fs::remove_all(dir_ / "out");
  fs::create_directories(dir_ / "out");
  JobLimits roomy;
  roomy.max_job_memory_bytes = kUnrefined + 100000ull * 2 * (256 + 1280);
  const JobOutput loose = run(job, roomy);
  ASSERT_TRUE(loose.report.mesh->refinement);
  EXPECT_EQ(loose.report.mesh->refinement->vertex_limit, 16 * 961);
  EXPECT_EQ(loose.report.mesh->refinement->stop, proto::RefinementStop::kFlipFree);
  EXPECT_EQ(loose.report.mesh->uvs.flipped_triangles, 0);
}

// A set whose targets are its sources mirrored (x → 64 − x): with "mirror": true the warp is the identity of the
// flipped texture, so warped.png is the input flipped, compared here pixel by pixel (flipped by index).
TEST_F(JobRunnerTest, MirrorFlipsTheTextureFirst) {
  nlohmann::json features = nlohmann::json::array();
  for (const auto& [x, y] : std::vector<std::pair<double, double>>{{10, 12}, {50, 20}, {30, 50}, {20, 35}}) {
    features.push_back({{"source", {x, y}}, {"target", {64.0 - x, y}}});
  }
  nlohmann::json job = testing::image_job();
  job["warp"]["features"] = features;
  job["warp"]["mirror"] = true;
  const JobOutput out = run(job);
  expect_report_round_trips(out);
  const proto::ImageJobReport& r = *out.report.image;
  ASSERT_TRUE(r.mirror);
  EXPECT_TRUE(r.mirror->detected);
  EXPECT_LT(r.mirror->residual_ratio, 1e-9);
  EXPECT_TRUE(r.mirror->applied);
  EXPECT_FALSE(r.mirror->suggestion);
  EXPECT_LT(r.residuals.max_px, 1e-3);

  const fs::path input = dir_ / "input.png";
  write_text_file_atomically(input.string(), testing::test_png(64));
  const Image original = read_image(input.string());
  const Image warped = read_image((dir_ / "out" / "warped.png").string());
  ASSERT_EQ(warped.width, 64);
  ASSERT_EQ(warped.channels, original.channels + 1);  // the transparent border's alpha
  double worst = 0.0;
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      for (int c = 0; c < original.channels; ++c) {
        worst = std::max(worst, static_cast<double>(std::abs(warped.pixel(x, y)[c] - original.pixel(63 - x, y)[c])));
      }
    }
  }
  EXPECT_LT(worst, 0.06);  // bilinear sampling within the lattice's 0.05 px, and 8-bit rounding
}

TEST_F(JobRunnerTest, SubmissionAndRunRefuseTheSameFaultsBeforeWritingAnything) {
  JobLimits few_features;
  few_features.max_features = 3;
  EXPECT_EQ(refusal(testing::image_job(), few_features), "$.warp.features: 4 features, more than the limit of 3");
  EXPECT_EQ(refusal(testing::mesh_job(), few_features),
            "$.mesh.features.features: 5 features, more than the limit of 3");

  JobLimits small_output;
  small_output.max_output_pixels = 100LL * 100;
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
