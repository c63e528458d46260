// The textured glTF: see gltf_output.hpp. The document is edited as JSON (not re-serialised through tinygltf's
// model), so that what texwarp does not understand (extensions, extras, images it never decodes) survives as read.
#include "texwarp/mesh/gltf_output.hpp"

#include <cstdint>
#include <cstring>
#include <vector>

#include "texwarp/proto/base64.hpp"

namespace texwarp::mesh {
namespace {

constexpr int kFloat = 5126;         // componentType FLOAT
constexpr int kArrayBuffer = 34962;  // bufferView target ARRAY_BUFFER

void put_u32(std::string& out, std::uint32_t v) {
  char b[4];
  std::memcpy(b, &v, 4);
  out.append(b, 4);
}

void pad_to_4(std::string& s, char fill) {
  while (s.size() % 4 != 0) s.push_back(fill);
}

nlohmann::json& array_of(nlohmann::json& doc, const char* key) {
  if (!doc.contains(key) || !doc[key].is_array()) doc[key] = nlohmann::json::array();
  return doc[key];
}

std::string glb_bytes(const nlohmann::json& doc, std::string bin) {
  std::string json = doc.dump();
  pad_to_4(json, ' ');
  pad_to_4(bin, '\0');
  std::string out;
  const std::size_t total = 12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size());
  out.reserve(total);
  put_u32(out, 0x46546C67);  // "glTF"
  put_u32(out, 2);
  put_u32(out, static_cast<std::uint32_t>(total));
  put_u32(out, static_cast<std::uint32_t>(json.size()));
  put_u32(out, 0x4E4F534A);  // "JSON"
  out += json;
  if (!bin.empty()) {
    put_u32(out, static_cast<std::uint32_t>(bin.size()));
    put_u32(out, 0x004E4942);  // "BIN\0"
    out += bin;
  }
  return out;
}

}  // namespace

std::string textured_gltf_bytes(const GltfMesh& gltf, const MeshRegion& region,
                                std::span<const std::array<double, 2>> uvs,
                                const std::optional<std::string>& base_color_uri) {
  std::vector<std::array<double, 2>> texcoord = gltf.texcoord0;
  for (const int f : region.faces) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = gltf.corners[3 * static_cast<std::size_t>(f) + k];
      texcoord[v] = uvs[region.local_vertex[gltf.mesh.faces[f][k]]];
    }
  }
  std::string data(texcoord.size() * 8, '\0');
  for (std::size_t i = 0; i < texcoord.size(); ++i) {
    const float uv[2] = {static_cast<float>(texcoord[i][0]), static_cast<float>(texcoord[i][1])};
    std::memcpy(data.data() + 8 * i, uv, 8);
  }

  nlohmann::json doc = gltf.document;
  nlohmann::json& buffers = array_of(doc, "buffers");
  std::string bin = gltf.binary_chunk;
  // .glb: buffer 0 is the BIN chunk when it has no URI; the UVs go at its end. Otherwise a new embedded buffer.
  const bool into_bin = gltf.binary && (buffers.empty() || !buffers[0].contains("uri"));
  std::size_t buffer = 0;
  std::size_t offset = 0;
  if (into_bin) {
    pad_to_4(bin, '\0');
    offset = bin.size();
    bin += data;
    if (buffers.empty()) buffers.push_back(nlohmann::json::object());
    buffers[0]["byteLength"] = bin.size();
  } else {
    buffer = buffers.size();
    buffers.push_back(
        {{"byteLength", data.size()}, {"uri", "data:application/octet-stream;base64," + proto::base64_encode(data)}});
  }
  nlohmann::json& views = array_of(doc, "bufferViews");
  views.push_back({{"buffer", buffer}, {"byteOffset", offset}, {"byteLength", data.size()}, {"target", kArrayBuffer}});
  nlohmann::json& accessors = array_of(doc, "accessors");
  accessors.push_back({{"bufferView", views.size() - 1},
                       {"componentType", kFloat},
                       {"count", texcoord.size()},
                       {"type", "VEC2"},
                       {"name", "texwarp TEXCOORD_0"}});
  nlohmann::json& primitive = doc["meshes"][gltf.mesh_index]["primitives"][gltf.primitive_index];
  primitive["attributes"]["TEXCOORD_0"] = accessors.size() - 1;

  if (base_color_uri) {
    nlohmann::json& images = array_of(doc, "images");
    images.push_back({{"uri", *base_color_uri}, {"name", "texwarp warped texture"}});
    nlohmann::json& textures = array_of(doc, "textures");
    textures.push_back({{"source", images.size() - 1}});
    nlohmann::json material = nlohmann::json::object();
    const nlohmann::json& materials_in = doc.contains("materials") ? doc["materials"] : nlohmann::json::array();
    if (primitive.contains("material") && primitive["material"].is_number_unsigned() &&
        primitive["material"].get<std::size_t>() < materials_in.size()) {
      material = materials_in[primitive["material"].get<std::size_t>()];
    }
    material["name"] =
        (material.contains("name") && material["name"].is_string() ? material["name"].get<std::string>() + " "
                                                                   : std::string()) +
        "(texwarp)";
    if (!material.contains("pbrMetallicRoughness") || !material["pbrMetallicRoughness"].is_object()) {
      material["pbrMetallicRoughness"] = {{"metallicFactor", 0.0}};
    }
    material["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", textures.size() - 1}, {"texCoord", 0}};
    nlohmann::json& materials = array_of(doc, "materials");
    materials.push_back(std::move(material));
    primitive["material"] = materials.size() - 1;
  }
  if (gltf.binary) return glb_bytes(doc, std::move(bin));
  return doc.dump(2) + "\n";
}

}  // namespace texwarp::mesh
