// The textured OBJ. From a mesh alone (a JSON mesh): every vertex in its order (vertex ids stay valid), one `vt` per
// region vertex (in region-vertex order), the region's faces as `f v/vt` and the other faces as plain `f v`. From an
// OBJ's text: every input line kept byte for byte except the region's f lines, whose vt indices point at new vt
// lines appended at the end (one per region vertex).
#pragma once

#include <array>
#include <span>
#include <string>
#include <string_view>

#include "texwarp/mesh/input_faces.hpp"
#include "texwarp/mesh/mesh_region.hpp"
#include "texwarp/mesh/triangle_mesh.hpp"

namespace texwarp::mesh {

// uvs: per region vertex (local id). `comment` lines go at the top, each prefixed with "# ".
std::string textured_obj_text(const TriangleMesh& mesh, const MeshRegion& region,
                              std::span<const std::array<double, 2>> uvs, const std::string& comment);

// The input OBJ `text` (as parse_obj_file read it into `mesh` and `faces`) with new UVs for the region: the comment
// lines first, then each input line unchanged but for the f lines of input faces whose triangles are all in the
// region, rewritten as `v/vt` or `v/vt/vn` (v and vn kept as written, vt the new one), then the new vt lines.
std::string textured_obj_text(std::string_view text, const TriangleMesh& mesh, const InputFaces& faces,
                              const MeshRegion& region, std::span<const std::array<double, 2>> uvs,
                              const std::string& comment);

// Writes it atomically (text_file.hpp).
void write_textured_obj(const std::string& path, const TriangleMesh& mesh, const MeshRegion& region,
                        std::span<const std::array<double, 2>> uvs, const std::string& comment);

}  // namespace texwarp::mesh
