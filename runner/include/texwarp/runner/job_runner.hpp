// Running a job (proto::JobSpec) through the pipeline: the image warp of an image job, or LSCM + surface
// features + warp of a mesh job; result files written atomically into a folder, plus the report. Shared by
// texwarpd's workers and `texwarp run`. Also the cheap checks made when a job is accepted.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "texwarp/core/image_io.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/runner/input_resolver.hpp"

namespace texwarp::runner {

struct JobLimits {
  ImageLimits image;                               // the texture's header is checked before any pixel is read
  long long max_output_pixels = 16384LL * 16384LL;  // warped image width × height
  std::size_t max_features = 1000;                 // the method is O(n²) per field evaluation
  long long max_mesh_bytes = 256LL << 20;          // a blob or path mesh file
  std::uint64_t max_job_memory_bytes = 0;          // what one job may allocate (pixels, output, lattice); 0: no limit
};

struct JobFile {
  std::string name;        // file name inside the output folder
  std::string media_type;
};

struct JobOutput {
  std::vector<JobFile> files;  // written, report.json last
  nlohmann::json report;       // the content of report.json
};

// The default memory budget of one job: half the machine's physical memory, shared by `concurrent_jobs` jobs
// (texwarpd's --workers; 1 for the command line).
std::uint64_t default_job_memory_bytes(int concurrent_jobs);

// Names of the result files.
inline constexpr const char* kReportFile = "report.json";
inline constexpr const char* kObjFile = "mesh.obj";
inline constexpr const char* kUvFile = "uvs.json";
std::string warped_image_file(const proto::OutputSpec& output);  // "warped.png" | "warped.tiff" | "warped.exr"

// Checks that need no pixels and no integration, as on submission: limits (features, output size), the
// image header (size, channels) through `inputs`, the job's memory estimate against limits.max_job_memory_bytes
// (memory_estimate.hpp: "$.image: this job needs about …"), the warp problem (duplicates, collisions), the device,
// the mesh job's region and surface features. InputError naming the JSON path of the offender ("$.warp.features[3]").
void validate_job(const proto::JobSpec& spec, InputResolver& inputs, const JobLimits& limits);

// Runs the job and writes its files into `out_dir` (which must exist); the memory estimate is checked again
// before any pixel is decoded (for a mesh job once more with the parsed mesh's face count). Progress from 0 to 1
// and cancellation through `control` (CanceledError). InputError for the job's own faults (JSON paths as above),
// NumericalError when the method cannot meet its guarantees, std::runtime_error for I/O.
JobOutput run_job(const proto::JobSpec& spec, InputResolver& inputs, BackendCache& backends,
                  const std::filesystem::path& out_dir, const JobLimits& limits, const RunControl& control);

// Media type of a result file by its name ("image/png", "model/obj", "application/json", ...).
std::string media_type_for(const std::string& file_name);

}  // namespace texwarp::runner
