// A job turned into a validated plan: inputs resolved, the texture's header read, limits and the memory budget
// checked, the problem built (image job: the warp problem; mesh job: surface features, region, and at run time the
// parsed mesh and its region). Every refusal of a job's input is made here, before any pixel is decoded; texwarpd
// plans each job on submission too (validate_job), so a job it accepts fails later only for what needs the run.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/udim_texture.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/mesh/mesh_file.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/region_spec.hpp"
#include "texwarp/mesh/surface_feature.hpp"
#include "texwarp/mesh/texture_mapping.hpp"
#include "texwarp/mesh/uv_convention.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/runner/input_resolver.hpp"
#include "texwarp/runner/job_runner.hpp"

namespace texwarp::runner {

// kSubmission: what needs no mesh parsing (a mesh file's size gives its memory estimate); kRun: also parses the
// mesh, checks the budget against its exact face count and cuts the region.
enum class PlanScope { kSubmission, kRun };

struct ImagePlan {
  WarpProblem problem;
};

struct MeshPlan {
  mesh::SurfaceFeatureSet features;
  std::optional<mesh::RegionSpec> region;  // none: the whole mesh
  mesh::UvOrigin uv_origin = mesh::UvOrigin::kBottomLeft;
  mesh::TextureMappingOptions mapping;  // texture and frame sizes, margin
  // kRun only:
  std::optional<mesh::TriangleMesh> mesh;
  mesh::MeshFile file;  // the mesh's format, input faces and OBJ text or glTF document (its triangles moved to `mesh`)
  std::optional<mesh::MeshRegion> selected;
  double load_seconds = 0.0;  // parsing the mesh and cutting the region
};

// One map an image job warps: its single "image" (named "warped"), or each of its "images" (a texture set).
struct PlannedMap {
  std::string name;                // images[i].name; "warped" for the single image
  proto::JsonPath where;           // $.image or $.images[i]: where its errors are
  std::string texture_file;        // on this machine; never shown in messages
  std::optional<UdimCanvas> udim;  // a path with <UDIM>: its tiles on this machine (texture_file is then empty)
  ImageHeader header;              // checked against the image limits; a UDIM texture's canvas
  TextureEncoding encoding;        // its role
  PixelFormat output_format = PixelFormat::kUint8;
  std::string image_file;  // "<name>.<file_format>"; a UDIM texture's "<name>.<UDIM>.<file_format>"
};

struct JobPlan {
  const proto::JobSpec* spec = nullptr;  // the job (outlives the plan)
  std::string texture_file;              // the (first) texture on this machine; never shown in messages
  ImageHeader header;                    // the (first) texture's, checked against the image limits
  PixelFormat output_format = PixelFormat::kUint8;
  std::string image_file;          // "warped.png" | "warped.tiff" | "warped.exr"
  ImageWarpOptions warp;           // interpolation, border, exact, tolerance; size: the output's; the first map's role
  std::vector<PlannedMap> maps;    // every map, in the job's order (one for a single image)
  std::optional<ImagePlan> image;  // exactly one of image, mesh
  std::optional<MeshPlan> mesh;
  double seconds = 0.0;  // planning
};

// InputError naming the JSON path of the offender ("$.warp.features[3]", "$.image: this job needs about …").
JobPlan plan_job(const proto::JobSpec& spec, InputResolver& inputs, const JobLimits& limits, PlanScope scope);

}  // namespace texwarp::runner
