// Textured OBJ output: see obj_output.hpp.
#include "texwarp/mesh/obj_output.hpp"

#include <charconv>
#include <cstdio>
#include <sstream>

#include "texwarp/core/text_file.hpp"

namespace texwarp::mesh {

std::string textured_obj_text(const TriangleMesh& mesh, const MeshRegion& region,
                              std::span<const std::array<double, 2>> uvs, const std::string& comment) {
  std::string out;
  out.reserve(static_cast<std::size_t>(mesh.vertex_count()) * 60 + static_cast<std::size_t>(mesh.face_count()) * 40);
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out += "# " + line + "\n";
  char buf[160];
  for (const Vec3& v : mesh.vertices) {  // shortest text that reads back to the same double
    out += "v";
    for (double x : {v.x, v.y, v.z}) {
      buf[0] = ' ';
      const auto end = std::to_chars(buf + 1, buf + sizeof buf, x).ptr;
      out.append(buf, end);
    }
    out += "\n";
  }
  for (const auto& uv : uvs) {
    std::snprintf(buf, sizeof buf, "vt %.10g %.10g\n", uv[0], uv[1]);
    out += buf;
  }
  for (int f = 0; f < mesh.face_count(); ++f) {
    const Face& t = mesh.faces[f];
    if (region.local_face[f] >= 0) {
      std::snprintf(buf, sizeof buf, "f %d/%d %d/%d %d/%d\n", t[0] + 1, region.local_vertex[t[0]] + 1, t[1] + 1,
                    region.local_vertex[t[1]] + 1, t[2] + 1, region.local_vertex[t[2]] + 1);
    } else {
      std::snprintf(buf, sizeof buf, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    out += buf;
  }
  return out;
}

void write_textured_obj(const std::string& path, const TriangleMesh& mesh, const MeshRegion& region,
                        std::span<const std::array<double, 2>> uvs, const std::string& comment) {
  write_text_file_atomically(path, textured_obj_text(mesh, region, uvs, comment));
}

}  // namespace texwarp::mesh
