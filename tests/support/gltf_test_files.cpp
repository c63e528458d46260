// glTF test files: see gltf_test_files.hpp.
#include "gltf_test_files.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "texwarp/proto/base64.hpp"

namespace texwarp::mesh::testing {
namespace {

template <typename T>
void put(std::string& out, T value) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  out.append(b, sizeof(T));
}

void align(std::string& out) {
  while (out.size() % 4 != 0) out.push_back('\0');
}

}  // namespace

GltfParts gltf_parts(const TriangleMesh& mesh, const GltfFileOptions& options) {
  std::vector<Vec3> positions;
  std::vector<std::uint32_t> indices;
  if (options.split) {
    for (const Face& f : mesh.faces) {
      for (const int v : f) {
        indices.push_back(static_cast<std::uint32_t>(positions.size()));
        positions.push_back(mesh.vertices[v]);
      }
    }
  } else {
    positions = mesh.vertices;
    for (const Face& f : mesh.faces) indices.insert(indices.end(), f.begin(), f.end());
  }
  const std::size_t n = positions.size();
  GltfParts parts;
  std::string& bin = parts.bin;
  nlohmann::json views = nlohmann::json::array();
  nlohmann::json accessors = nlohmann::json::array();
  nlohmann::json attributes;
  const auto add_view = [&](std::size_t offset, std::size_t length, int stride) {
    nlohmann::json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", length}};
    if (stride > 0) v["byteStride"] = stride;
    views.push_back(v);
    return views.size() - 1;
  };
  const auto add_accessor = [&](std::size_t view, std::size_t offset, int type, std::size_t count, const char* shape) {
    accessors.push_back(
        {{"bufferView", view}, {"byteOffset", offset}, {"componentType", type}, {"count", count}, {"type", shape}});
    return accessors.size() - 1;
  };
  // POSITION (+ NORMAL)
  const std::size_t start = bin.size();
  for (std::size_t i = 0; i < n; ++i) {
    for (const double c : {positions[i].x, positions[i].y, positions[i].z}) put(bin, static_cast<float>(c));
    if (options.interleaved) {
      for (const float c : {0.0F, 0.0F, 1.0F}) put(bin, c);
    }
  }
  if (options.interleaved) {
    const std::size_t view = add_view(start, bin.size() - start, 24);
    attributes["POSITION"] = add_accessor(view, 0, 5126, n, "VEC3");
    attributes["NORMAL"] = add_accessor(view, 12, 5126, n, "VEC3");
  } else {
    attributes["POSITION"] = add_accessor(add_view(start, bin.size() - start, 0), 0, 5126, n, "VEC3");
    const std::size_t normals = bin.size();
    for (std::size_t i = 0; i < n; ++i) {
      for (const float c : {0.0F, 0.0F, 1.0F}) put(bin, c);
    }
    attributes["NORMAL"] = add_accessor(add_view(normals, bin.size() - normals, 0), 0, 5126, n, "VEC3");
  }
  Vec3 lo = positions[0];
  Vec3 hi = positions[0];
  for (const Vec3& p : positions) {
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  accessors[attributes["POSITION"].get<std::size_t>()]["min"] = {static_cast<float>(lo.x), static_cast<float>(lo.y),
                                                                 static_cast<float>(lo.z)};
  accessors[attributes["POSITION"].get<std::size_t>()]["max"] = {static_cast<float>(hi.x), static_cast<float>(hi.y),
                                                                 static_cast<float>(hi.z)};
  const std::size_t uv0 = bin.size();
  for (std::size_t i = 0; i < n; ++i) {
    put(bin, static_cast<float>(positions[i].x / 10));
    put(bin, static_cast<float>(positions[i].y / 10));
  }
  attributes["TEXCOORD_0"] = add_accessor(add_view(uv0, bin.size() - uv0, 0), 0, 5126, n, "VEC2");
  const std::size_t uv1 = bin.size();
  for (std::size_t i = 0; i < n; ++i) {
    put(bin, 0.25F);
    put(bin, 0.75F);
  }
  attributes["TEXCOORD_1"] = add_accessor(add_view(uv1, bin.size() - uv1, 0), 0, 5126, n, "VEC2");
  nlohmann::json primitive = {{"attributes", attributes}, {"material", 0}, {"mode", 4}};
  if (options.index_type != 0) {
    const std::size_t at = bin.size();
    for (const std::uint32_t i : indices) {
      if (options.index_type == 5121) put(bin, static_cast<std::uint8_t>(i));
      if (options.index_type == 5123) put(bin, static_cast<std::uint16_t>(i));
      if (options.index_type == 5125) put(bin, i);
    }
    primitive["indices"] =
        add_accessor(add_view(at, bin.size() - at, 0), 0, options.index_type, indices.size(), "SCALAR");
    align(bin);
  }
  parts.json = {
      {"asset", {{"version", "2.0"}, {"generator", "texwarp tests"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}, {"name", "grid node"}, {"translation", {1.0, 2.0, 3.0}}}}},
      {"meshes", {{{"name", options.mesh_name}, {"primitives", {primitive}}}}},
      {"materials", {{{"name", "paint"}, {"pbrMetallicRoughness", {{"baseColorFactor", {1, 0.5, 0.25, 1}}}}}}},
      {"buffers", {{{"byteLength", bin.size()}}}},
      {"bufferViews", views},
      {"accessors", accessors}};
  return parts;
}

std::string gltf_text(GltfParts parts) {
  parts.json["buffers"][0]["uri"] = "data:application/octet-stream;base64," + proto::base64_encode(parts.bin);
  return parts.json.dump(1);
}

std::string glb_bytes(const GltfParts& parts) {
  std::string json = parts.json.dump();
  while (json.size() % 4 != 0) json.push_back(' ');
  std::string bin = parts.bin;
  align(bin);
  std::string out;
  put(out, std::uint32_t{0x46546C67});
  put(out, std::uint32_t{2});
  put(out, static_cast<std::uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  put(out, static_cast<std::uint32_t>(json.size()));
  put(out, std::uint32_t{0x4E4F534A});
  out += json;
  put(out, static_cast<std::uint32_t>(bin.size()));
  put(out, std::uint32_t{0x004E4942});
  out += bin;
  return out;
}

}  // namespace texwarp::mesh::testing
