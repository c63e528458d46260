// The mesh mapping report (proto::MeshMappingReport): sizes, the LSCM and warp set-up, the quality of the UVs into
// the original texture (l2_stretch, l2_shear, flipped_triangles, max_residual_px, ...), of the UVs into the warped
// texture, and per feature its surface place and residual; per triangle and per vertex on request.
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/mesh/texture_mapping.hpp"
#include "texwarp/mesh/uv_convention.hpp"
#include "texwarp/proto/job_report.hpp"

namespace texwarp::mesh {

struct MappingReportOptions {
  UvOrigin uv_origin = UvOrigin::kBottomLeft;
  bool per_triangle = false;  // "triangles": needs `quality` computed with per_triangle
  bool per_vertex = false;    // "vertices": mesh id, uv (original texture), warped_uv
  double total_seconds = 0.0;
};

proto::MeshMappingReport mesh_mapping_report(const TriangleMesh& mesh, const TextureMapping& mapping,
                                             const MappingQuality& quality, const TextureMappingOptions& options,
                                             const MappingReportOptions& report);

// The same as JSON (`texwarp map-mesh --report`): proto::encode_mesh_mapping_report of the above.
nlohmann::json mapping_report(const TriangleMesh& mesh, const TextureMapping& mapping, const MappingQuality& quality,
                              const TextureMappingOptions& options, const MappingReportOptions& report);

}  // namespace texwarp::mesh
