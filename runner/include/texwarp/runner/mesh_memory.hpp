// What a mesh job holds besides its image warp, per face of the mesh, and how far refinement may grow a region within
// a memory budget: one model for texwarpd's jobs (job_plan.cpp) and `texwarp map-mesh`.
#pragma once

#include <cstdint>

#include "texwarp/core/memory_estimate.hpp"

namespace texwarp::runner {

// Per mesh face (a vertex per two faces): alive throughout, the mesh, its topology, the region and the mapping's
// arrays, the OBJ and UV texts (~256 bytes); while flattening, the LSCM system (12 triplets and 12 non-zeros per
// face), its normal matrix and their LDLᵀ factor with its fill (~1.3 kB).
inline constexpr std::uint64_t kMeshResidentBytesPerFace = 256;
inline constexpr std::uint64_t kMeshSolveBytesPerFace = 1280;

struct MeshSize {
  std::uint64_t faces = 0;       // exact once parsed, else estimated
  std::uint64_t text_bytes = 0;  // a mesh file or OBJ text, held whole while it is parsed
  bool estimated = false;
  std::uint64_t held_bytes = 0;  // what the parsed file keeps for the output throughout (a glTF's: GltfMesh)
};

// The mesh alive throughout a job (beside the image warp's buffers).
MemoryPhase mesh_resident(const MeshSize& size);

// The mesh while it is flattened: resident, the LSCM system and its factor, the mesh text.
MemoryPhase mesh_flattening(const MeshSize& size);

// Refinement's bound on the region's vertices from what the budget leaves once the unrefined job fits: each vertex it
// adds brings about two faces, held and flattened (and optimised) like the input's. 0: no budget, no such bound.
int refined_vertex_budget(std::uint64_t budget_bytes, std::uint64_t unrefined_peak_bytes, int region_vertices);

}  // namespace texwarp::runner
