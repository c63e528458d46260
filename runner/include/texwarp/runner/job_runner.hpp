// Running a job (proto::JobSpec) through the pipeline: planned (every check of its input), then run: the image
// warp of an image job, or LSCM + surface features + warp of a mesh job; result files written atomically into a
// folder, plus the typed report. Shared by texwarpd's workers and `texwarp run`; texwarpd plans jobs on submission.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "texwarp/core/image_io.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/job_report.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/runner/input_resolver.hpp"

namespace texwarp::runner {

struct JobLimits {
  ImageLimits image;                                // the texture's header is checked before any pixel is read
  long long max_output_pixels = 16384LL * 16384LL;  // warped image width × height
  std::size_t max_features = 1000;                  // the method is O(n²) per field evaluation
  long long max_mesh_bytes = 256LL << 20;           // a blob or path mesh file
  std::uint64_t max_job_memory_bytes = 0;           // what one job may allocate (pixels, output, lattice); 0: no limit
};

struct JobFile {
  std::string name;  // file name inside the output folder
  std::string media_type;
  std::optional<proto::ImageRole> role = std::nullopt;  // a warped image: the role its map was sampled with
};

struct JobOutput {
  std::vector<JobFile> files;  // written, report.json last
  proto::JobReport report;     // the content of report.json (proto::encode_job_report)
};

// The default memory budget of one job: half the machine's physical memory, shared by `concurrent_jobs` jobs
// (texwarpd's --workers; 1 for the command line).
std::uint64_t default_job_memory_bytes(int concurrent_jobs);

// Names of the result files.
inline constexpr const char* kReportFile = "report.json";
inline constexpr const char* kObjFile = "mesh.obj";    // OBJ, JSON and inline meshes
inline constexpr const char* kGltfFile = "mesh.gltf";  // a .gltf mesh written back
inline constexpr const char* kGlbFile = "mesh.glb";    // a .glb mesh written back
inline constexpr const char* kUvFile = "uvs.json";
// A warped image's extension: the file format's ("png", "tiff", "exr"), "tx" for a TIFF texture (output.texture).
std::string warped_image_extension(const proto::OutputSpec& output);
std::string warped_image_file(const proto::OutputSpec& output);  // "warped." + warped_image_extension

// The job's plan as on submission, made by the same planning step as run_job's and kept for nothing: the device,
// the image header (size, channels) through `inputs`, limits (features, output size), the job's memory estimate
// against limits.max_job_memory_bytes (memory_estimate.hpp: "$.image: this job needs about …"), the warp problem
// (duplicates, collisions), the mesh job's region and surface features (its mesh is not parsed: its memory is
// estimated from its size). InputError naming the JSON path of the offender ("$.warp.features[3]").
void validate_job(const proto::JobSpec& spec, InputResolver& inputs, const JobLimits& limits);

// Plans the job (as validate_job; a mesh job's plan also parses the mesh, checks its memory again with the exact
// face count and cuts the region), then runs the plan and writes its files into `out_dir` (which must exist). No
// pixel is decoded before the plan stands; a mesh job's surface features are placed (and may be refused) after
// its LSCM, still before. Progress from 0 to 1 and cancellation through `control` (CanceledError). InputError for the
// job's own faults (JSON paths as above), NumericalError when the method cannot meet its guarantees, std::runtime_error
// for I/O.
JobOutput run_job(const proto::JobSpec& spec, InputResolver& inputs, BackendCache& backends,
                  const std::filesystem::path& out_dir, const JobLimits& limits, const RunControl& control);

// Media type of a result file by its name ("image/png", "model/obj", "application/json", ...).
std::string media_type_for(const std::string& file_name);

}  // namespace texwarp::runner
