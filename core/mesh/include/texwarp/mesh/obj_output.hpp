// The textured OBJ: every input vertex in its order (vertex ids stay valid), one `vt` per region vertex (in
// region-vertex order), the region's faces as `f v/vt` and the other faces as plain `f v`, in input order.
#pragma once

#include <array>
#include <span>
#include <string>

#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

// uvs: per region vertex (local id). `comment` lines go at the top, each prefixed with "# ".
std::string textured_obj_text(const TriangleMesh& mesh, const MeshRegion& region,
                              std::span<const std::array<double, 2>> uvs, const std::string& comment);

// Writes it atomically (text_file.hpp).
void write_textured_obj(const std::string& path, const TriangleMesh& mesh, const MeshRegion& region,
                        std::span<const std::array<double, 2>> uvs, const std::string& comment);

}  // namespace texwarp::mesh
