// A mesh job's memory model: see mesh_memory.hpp.
#include "texwarp/runner/mesh_memory.hpp"

#include <algorithm>
#include <limits>
#include <string>

namespace texwarp::runner {

MemoryPhase mesh_resident(const MeshSize& size) {
  MemoryPhase resident = {{"mesh of " + std::string(size.estimated ? "about " : "") + std::to_string(size.faces) +
                               " faces (topology, region, UVs)",
                           size.faces * kMeshResidentBytesPerFace}};
  if (size.held_bytes > 0)
    resident.push_back({"the glTF document and attributes kept for the output", size.held_bytes});
  return resident;
}

MemoryPhase mesh_flattening(const MeshSize& size) {
  MemoryPhase flattening = mesh_resident(size);
  flattening.push_back({"LSCM system and factor", size.faces * kMeshSolveBytesPerFace});
  flattening.push_back({"mesh text", size.text_bytes});
  return flattening;
}

int refined_vertex_budget(std::uint64_t budget_bytes, std::uint64_t unrefined_peak_bytes, int region_vertices) {
  if (budget_bytes == 0) return 0;
  const std::uint64_t left = budget_bytes > unrefined_peak_bytes ? budget_bytes - unrefined_peak_bytes : 0;
  const std::uint64_t more = left / (2 * (kMeshResidentBytesPerFace + kMeshSolveBytesPerFace));
  return static_cast<int>(
      std::min<std::uint64_t>(static_cast<std::uint64_t>(region_vertices) + more, std::numeric_limits<int>::max()));
}

}  // namespace texwarp::runner
