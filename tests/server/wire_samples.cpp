// texwarp_wire_samples DIR: writes what the codecs and a real job run produce (canonical jobs, statuses, a page, a
// problem, a blob answer, image and mesh job results with their real reports, report.json files of image and mesh
// jobs) and documents the job schema must refuse, for validate_against_schemas.py to check with a JSON Schema
// 2020-12 validator.
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>

#include "scratch_resolver.hpp"
#include "test_jobs.hpp"
#include "texwarp/core/text_file.hpp"
#include "texwarp/proto/blob_info_codec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_batch_codec.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/job_result_codec.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/job_status_codec.hpp"
#include "texwarp/proto/node_status_codec.hpp"
#include "texwarp/proto/problem_details_codec.hpp"
#include "texwarp/runner/job_runner.hpp"
#include "texwarp/server/problem_types.hpp"
#include "texwarp/server/sha256.hpp"

namespace {

using texwarp::testing::ScratchResolver;

namespace fs = std::filesystem;
using namespace texwarp;

void write(const fs::path& dir, const std::string& name, const nlohmann::json& doc) {
  std::ofstream(dir / name) << doc.dump(2) << "\n";
}

// Runs the job; its report.json is kept as report-<name>.json.

nlohmann::json real_result(const nlohmann::json& job, const fs::path& dir, const std::string& name) {
  const proto::JobSpec spec = proto::decode_job_spec(job);
  const fs::path out = dir / (name + "-files");
  fs::create_directories(out);
  ScratchResolver inputs(dir);
  runner::BackendCache backends(proto::DeviceSpec::cpu());
  const runner::JobOutput output = runner::run_job(spec, inputs, backends, out, {}, {});
  proto::JobResult result;
  result.job_id = "job_abcdefghijklmnopqrstuvwxyz";
  result.kind = spec.kind();
  for (const auto& f : output.files) {
    proto::ResultFile file;
    file.name = f.name;
    file.media_type = f.media_type;
    file.sha256 = server::sha256_file_hex(out / f.name, &file.bytes);
    file.href = "/v1/jobs/" + result.job_id + "/files/" + f.name;
    file.role = f.role;
    result.files.push_back(file);
  }
  result.report_json = proto::encode_job_report(output.report).dump();
  fs::copy_file(out / runner::kReportFile, dir / ("report-" + name + ".json"));
  return proto::encode_job_result(result);
}

int run(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DIR\n", argv[0]);
    return 2;
  }
  const fs::path dir(argv[1]);
  fs::create_directories(dir);
  const nlohmann::json image = testing::image_job(80);
  const nlohmann::json mesh = testing::mesh_job();
  write(dir, "job-image.json", proto::encode_job_spec(proto::decode_job_spec(image)));
  write(dir, "job-mesh.json", proto::encode_job_spec(proto::decode_job_spec(mesh)));
  nlohmann::json blob_job = image;
  blob_job["image"] = {{"blob", "sha256:" + std::string(64, 'c')}};
  blob_job["options"] = {{"exact", true}, {"device", "opencl:pocl"}, {"jacobian_check", true}};
  write(dir, "job-blob.json", proto::encode_job_spec(proto::decode_job_spec(blob_job)));

  proto::JobStatus s;
  s.id = "job_abcdefghijklmnopqrstuvwxyz";
  s.name = "sample";
  s.created_at = "2024-05-01T12:00:00.123Z";
  write(dir, "status-queued.json", proto::encode_job_status(s));
  s.state = proto::JobState::kFailed;
  s.attempts = 1;
  s.progress = 30;
  s.started_at = "2024-05-01T12:00:01.000Z";
  s.finished_at = "2024-05-01T12:00:02.000Z";
  s.error = server::job_problem(server::ErrorKind::kInvalidJob, "$.mesh.region: not a disk", "$.mesh.region");
  write(dir, "status-failed.json", proto::encode_job_status(s));
  s.state = proto::JobState::kSucceeded;
  s.error.reset();
  s.progress = 100;
  write(dir, "status-succeeded.json", proto::encode_job_status(s));
  write(dir, "page.json", proto::encode_job_page({{s, s}, "42"}));
  s.priority = -3;
  s.labels = {{"shot", "sq010/sh0040"}, {"dept", "lookdev"}};
  s.node = "farm-2:8080";
  write(dir, "status-labelled.json", proto::encode_job_status(s));
  write(dir, "batch-status.json", proto::encode_job_batch_status({{s, s}}));
  nlohmann::json tagged = image;
  tagged["priority"] = 1000;
  tagged["labels"] = {{"shot", "sq010/sh0040"}, {"a.b-c_d/E9", ""}};
  const proto::JobBatch batch = proto::decode_job_batch({{"jobs", {image, mesh, tagged}}});
  write(dir, "batch-jobs.json", proto::encode_job_batch(batch));
  proto::NodeStatus node{"farm-2:8080",
                         "10.0.0.2:8080",
                         "1.0.0",
                         4,
                         4242,
                         "2024-05-01T12:00:00.000Z",
                         "2024-05-01T12:05:00.000Z",
                         true,
                         2};
  write(dir, "nodes.json", proto::encode_node_list({{node}}));
  write(dir, "problem.json",
        proto::encode_problem(
            server::to_problem(server::ServiceError(server::ErrorKind::kQueueFull, "retry later"), "/v1/jobs")));
  write(dir, "blob.json", proto::encode_blob_info({"sha256:" + std::string(64, 'd'), 12, true}));
  write(dir, "result-image.json", real_result(image, dir, "image"));
  write(dir, "result-mesh.json", real_result(mesh, dir, "mesh"));
  // A texture set: two maps of the test pattern, one as colour, one as data.
  nlohmann::json set = image;
  set.erase("image");
  set["images"] = {{{"base64", image["image"]["base64"]}, {"name", "albedo"}, {"role", "color"}},
                   {{"base64", image["image"]["base64"]}, {"name", "mask"}, {"role", "data"}}};
  write(dir, "job-set.json", proto::encode_job_spec(proto::decode_job_spec(set)));
  write(dir, "result-set.json", real_result(set, dir, "set"));
  // The set on a mesh job's region (its report lists the maps), and a UDIM texture given tile by tile.
  nlohmann::json mesh_set = mesh;
  mesh_set.erase("image");
  mesh_set["images"] = set["images"];
  write(dir, "job-mesh-set.json", proto::encode_job_spec(proto::decode_job_spec(mesh_set)));
  write(dir, "result-mesh-set.json", real_result(mesh_set, dir, "mesh-set"));
  nlohmann::json tiles = image;
  tiles.erase("output");
  tiles["image"] = {{"tiles",
                     {{{"tile", 1001}, {"base64", image["image"]["base64"]}},
                      {{"tile", 1012}, {"base64", image["image"]["base64"]}}}},
                    {"role", "color"}};
  write(dir, "job-udim-tiles.json", proto::encode_job_spec(proto::decode_job_spec(tiles)));
  write(dir, "result-udim-tiles.json", real_result(tiles, dir, "udim-tiles"));
  nlohmann::json blob_tiles = tiles;
  blob_tiles["image"]["tiles"] = {{{"tile", 1001}, {"blob", "sha256:" + std::string(64, 'e')}}};
  write(dir, "job-udim-blob-tiles.json", proto::encode_job_spec(proto::decode_job_spec(blob_tiles)));
  nlohmann::json checked = image;
  checked["options"] = {{"exact", true}, {"jacobian_check", true}};
  real_result(checked, dir, "image-jacobian");
  nlohmann::json uvs_only = mesh;
  uvs_only["output"] = {{"image", false}};
  uvs_only["mesh"]["per_triangle"] = true;
  uvs_only["mesh"]["per_vertex"] = true;
  real_result(uvs_only, dir, "mesh-uvs-only");

  // Documents the codec refuses: the schema must refuse them too.
  nlohmann::json bad = image;
  bad["warp"]["features"][0]["colour"] = 1;
  write(dir, "invalid-unknown-key.json", bad);
  bad = image;
  bad["mesh"] = mesh["mesh"];
  write(dir, "invalid-both-kinds.json", bad);
  bad = image;
  bad["warp"].erase("features");
  write(dir, "invalid-no-features.json", bad);
  bad = mesh;
  bad["mesh"]["source"] = {{"blob", "sha256:" + std::string(64, 'c')}};
  write(dir, "invalid-blob-without-format.json", bad);
  bad = image;
  bad["image"]["path"] = "/also/a/path";
  write(dir, "invalid-two-images.json", bad);
  bad = set;
  bad["image"] = image["image"];
  write(dir, "invalid-image-and-images.json", bad);
  bad = set;
  bad["images"][1]["name"] = "../mask";
  write(dir, "invalid-image-name.json", bad);
  bad = set;
  bad["images"] = nlohmann::json::array();
  write(dir, "invalid-no-images.json", bad);
  bad = tiles;
  bad["image"]["tiles"][0]["tile"] = 1101;
  write(dir, "invalid-tile-number.json", bad);
  bad = tiles;
  bad["image"]["tiles"][0].erase("base64");
  write(dir, "invalid-tile-without-file.json", bad);
  bad = tiles;
  bad["image"]["tiles"][0]["blob"] = "sha256:" + std::string(64, 'e');
  write(dir, "invalid-tile-with-two-files.json", bad);
  bad = tiles;
  bad["image"]["path"] = "a.<UDIM>.png";
  write(dir, "invalid-tiles-and-path.json", bad);
  bad = image;
  bad["output"] = {{"width", 0}};
  write(dir, "invalid-width.json", bad);
  bad = image;
  bad["warp"]["features"][3].erase("target_frame");
  write(dir, "invalid-half-gradient.json", bad);
  bad = image;
  bad["priority"] = 1001;
  write(dir, "invalid-priority.json", bad);
  bad = image;
  bad["labels"] = {{"shot name", "x"}};
  write(dir, "invalid-label-key.json", bad);
  bad = image;
  bad["labels"] = {{"shot", std::string(257, 'v')}};
  write(dir, "invalid-label-value.json", bad);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "texwarp_wire_samples: %s\n", e.what());
    return 1;
  }
}
