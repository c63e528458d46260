// The region a RegionSpec (proto/region_spec.hpp: a face set, or a vertex curve and a seed face) selects on a mesh.
#pragma once

#include <optional>

#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"
#include "texwarp/proto/input_location.hpp"
#include "texwarp/proto/region_spec.hpp"

namespace texwarp::mesh {

using proto::RegionSpec;

// The region on `mesh` (validated): the whole mesh when `spec` is empty. `where` is the region document (a file
// for the CLI, none in a job; the mesh's when there is no region); an id that is out of range is named by its JSON
// path in it ("$.faces[3]").
MeshRegion select_region(const TriangleMesh& mesh, const std::optional<RegionSpec>& spec,
                         const proto::InputLocation& where);

}  // namespace texwarp::mesh
