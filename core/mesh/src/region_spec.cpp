// Region selection: see region_spec.hpp.
#include "texwarp/mesh/region_spec.hpp"

#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {

MeshRegion select_region(const TriangleMesh& mesh, const std::optional<RegionSpec>& spec, const InputLocation& where) {
  if (!spec) return whole_mesh_region(mesh, where);
  // A place in the region document.
  const auto at = [&](JsonPath path) { return InputLocation(std::move(path)).in_file(where.file_name()); };
  if (!spec->is_curve()) {
    for (std::size_t i = 0; i < spec->faces.size(); ++i) {
      if (spec->faces[i] >= mesh.face_count()) {
        throw InputError(at(JsonPath{"faces"}.index(i)), "face " + std::to_string(spec->faces[i]) +
                                                             " does not exist (the mesh has " +
                                                             std::to_string(mesh.face_count()) + " faces)");
      }
    }
    return disk_region(mesh, spec->faces, where);
  }
  for (std::size_t i = 0; i < spec->boundary.size(); ++i) {
    if (spec->boundary[i] >= mesh.vertex_count()) {
      throw InputError(at(JsonPath{"boundary"}.index(i)), "vertex " + std::to_string(spec->boundary[i]) +
                                                              " does not exist (the mesh has " +
                                                              std::to_string(mesh.vertex_count()) + " vertices)");
    }
  }
  if (spec->seed_face >= mesh.face_count()) {
    throw InputError(at(JsonPath{"seed_face"}), "face " + std::to_string(spec->seed_face) +
                                                    " does not exist (the mesh has " +
                                                    std::to_string(mesh.face_count()) + " faces)");
  }
  const std::vector<int> curve = close_vertex_curve(mesh, spec->boundary, where);
  return disk_region(mesh, faces_inside_curve(mesh, curve, spec->seed_face, where), where);
}

}  // namespace texwarp::mesh
