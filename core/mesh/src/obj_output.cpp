// Textured OBJ output: see obj_output.hpp.
#include "texwarp/mesh/obj_output.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <sstream>
#include <string_view>
#include <vector>

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
      auto* const end = std::to_chars(buf + 1, buf + sizeof buf, x).ptr;
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

namespace texwarp::mesh {
namespace {

// Whitespace-separated tokens of one line (the line without its end-of-line characters).
std::vector<std::string_view> tokens_of(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t at = 0;
  while (at < line.size()) {
    while (at < line.size() && (line[at] == ' ' || line[at] == '\t' || line[at] == '\r')) ++at;
    const std::size_t start = at;
    while (at < line.size() && line[at] != ' ' && line[at] != '\t' && line[at] != '\r') ++at;
    if (at > start) out.push_back(line.substr(start, at - start));
  }
  return out;
}

bool is_face_line(const std::vector<std::string_view>& tokens) { return tokens.size() >= 4 && tokens[0] == "f"; }

}  // namespace

std::string textured_obj_text(std::string_view text, const TriangleMesh& mesh, const InputFaces& faces,
                              const MeshRegion& region, std::span<const std::array<double, 2>> uvs,
                              const std::string& comment) {
  // An input face is rewritten when all of its triangles are in the region; its corners then name region vertices.
  std::vector<char> rewrite(static_cast<std::size_t>(faces.count()), 1);
  for (int t = 0; t < mesh.face_count(); ++t) {
    if (region.local_face[t] < 0) rewrite[faces.of_triangle[t]] = 0;
  }
  // The vt lines of the input: the new ones are numbered after them.
  int vt_count = 0;
  int face_count = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    const auto tokens = tokens_of(text.substr(at, end - at));
    if (!tokens.empty() && tokens[0] == "vt") ++vt_count;
    if (is_face_line(tokens)) ++face_count;
    at = end + 1;
  }
  if (face_count != faces.count()) {  // lines this scan reads otherwise than tinyobjloader: write the plain form
    return textured_obj_text(mesh, region, uvs, comment + "\n(input lines not kept: its f lines did not scan)");
  }
  std::string out;
  out.reserve(text.size() + uvs.size() * 32 + 256);
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out += "# " + line + "\n";
  int v_count = 0;
  int face = 0;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t newline = text.find('\n', at);
    const std::size_t end = newline == std::string_view::npos ? text.size() : newline;
    const std::string_view line = text.substr(at, end - at);
    const auto tokens = tokens_of(line);
    if (!tokens.empty() && tokens[0] == "v") ++v_count;
    if (is_face_line(tokens) && rewrite[face++]) {
      std::string f = "f";
      for (std::size_t k = 1; k < tokens.size(); ++k) {
        const std::string_view corner = tokens[k];
        const std::size_t slash = corner.find('/');
        const std::string_view v_text = corner.substr(0, slash);
        int v = 0;
        std::from_chars(v_text.data(), v_text.data() + v_text.size(), v);
        v = v < 0 ? v_count + v : v - 1;  // parse_obj_file checked every index
        f += " ";
        f += v_text;
        f += "/" + std::to_string(vt_count + region.local_vertex[v] + 1);
        const std::size_t second = slash == std::string_view::npos ? slash : corner.find('/', slash + 1);
        if (second != std::string_view::npos) f += corner.substr(second);  // "/vn"
      }
      out += f;
      if (!line.empty() && line.back() == '\r') out += '\r';
    } else {
      out += line;
    }
    if (newline != std::string_view::npos) out += '\n';
    at = end + 1;
  }
  if (!text.empty() && text.back() != '\n') out += '\n';
  char buf[96];
  for (const auto& uv : uvs) {
    std::snprintf(buf, sizeof buf, "vt %.10g %.10g\n", uv[0], uv[1]);
    out += buf;
  }
  return out;
}

}  // namespace texwarp::mesh
