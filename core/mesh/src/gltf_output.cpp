// The textured glTF: see gltf_output.hpp. The document is edited as JSON (not re-serialised through tinygltf's
// model), so that what texwarp does not understand (extensions, extras, images it never decodes) survives as read.
#include "texwarp/mesh/gltf_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

#include "texwarp/mesh/tiny_gltf.hpp"
#include "texwarp/mesh/triangle_geometry.hpp"
#include "texwarp/proto/base64.hpp"

namespace texwarp::mesh {
namespace {

void pad_to_4(std::string& s, char fill) {
  while (s.size() % 4 != 0) s.push_back(fill);
}

nlohmann::json& array_of(nlohmann::json& doc, const char* key) {
  if (!doc.contains(key) || !doc[key].is_array()) doc[key] = nlohmann::json::array();
  return doc[key];
}

const char* element_type(int components) {
  static constexpr const char* kTypes[] = {"SCALAR", "VEC2", "VEC3", "VEC4"};
  return kTypes[components - 1];
}

// Where the new data goes: at the end of a .glb's BIN chunk (buffer 0 when it has no URI), else into one new embedded
// buffer; each block gets its own buffer view, 4-byte aligned.
class DataSink {
 public:
  DataSink(nlohmann::json& doc, const GltfMesh& gltf) : doc_(doc), bin_(gltf.binary_chunk) {
    const nlohmann::json& buffers = array_of(doc_, "buffers");
    into_bin_ = gltf.binary && (buffers.empty() || !buffers[0].contains("uri"));
    buffer_ = into_bin_ ? 0 : buffers.size();
  }

  // A new accessor of `count` elements over `data`; returns its index.
  std::size_t accessor(const std::string& data, int target, int byte_stride, nlohmann::json accessor) {
    std::string& out = into_bin_ ? bin_ : extra_;
    pad_to_4(out, '\0');
    nlohmann::json view = {{"buffer", buffer_}, {"byteOffset", out.size()}, {"byteLength", data.size()}};
    if (target != 0) view["target"] = target;
    if (byte_stride != 0) view["byteStride"] = byte_stride;
    out += data;
    nlohmann::json& views = array_of(doc_, "bufferViews");
    views.push_back(std::move(view));
    accessor["bufferView"] = views.size() - 1;
    nlohmann::json& accessors = array_of(doc_, "accessors");
    accessors.push_back(std::move(accessor));
    return accessors.size() - 1;
  }

  // The buffers' final lengths (or the new embedded one); returns the BIN chunk's payload.
  std::string finish() {
    nlohmann::json& buffers = array_of(doc_, "buffers");
    if (into_bin_) {
      pad_to_4(bin_, '\0');
      if (buffers.empty()) buffers.push_back(nlohmann::json::object());
      buffers[0]["byteLength"] = bin_.size();
    } else if (!extra_.empty()) {
      buffers.push_back({{"byteLength", extra_.size()},
                         {"uri", "data:application/octet-stream;base64," + proto::base64_encode(extra_)}});
    }
    return std::move(bin_);
  }

 private:
  nlohmann::json& doc_;
  std::string bin_;
  std::string extra_;
  bool into_bin_ = false;
  std::size_t buffer_ = 0;
};

template <typename T>
void append_value(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(b, sizeof(T));
}

// A new glTF vertex inside an input triangle: the triangle's glTF vertices and its weights on them.
struct InterpolatedVertex {
  std::array<std::uint32_t, 3> corners{};
  Barycentric weights{};
  int nearest() const {
    int k = 0;
    for (int j = 1; j < 3; ++j) {
      if (weights[j] > weights[k]) k = j;
    }
    return k;
  }
};

// The refined primitive's glTF vertices: the input's, then one per new mesh vertex and set of glTF vertices around it.
class RefinedVertices {
 public:
  RefinedVertices(const GltfMesh& gltf, const MeshRefinement& refinement)
      : gltf_(gltf), refinement_(refinement), input_vertices_(gltf.mesh.vertex_count()) {}

  // The glTF vertex of output face f's corner k.
  std::uint32_t corner(int f, int k) {
    const int w = refinement_.mesh.faces[f][k];
    const int s = refinement_.source_face[f];
    const auto gltf_corner = [&](int j) { return gltf_.corners[3 * static_cast<std::size_t>(s) + j]; };
    if (w < input_vertices_) {
      for (int j = 0; j < 3; ++j) {
        if (gltf_.mesh.faces[s][j] == w) return gltf_corner(j);
      }
      throw std::logic_error("refined glTF: vertex " + std::to_string(w) + " is not a corner of its input face " +
                             std::to_string(s));
    }
    InterpolatedVertex v;
    v.weights = weights_in(w, s);
    std::array<std::uint32_t, 3> key{kNone, kNone, kNone};
    for (int j = 0; j < 3; ++j) {
      v.corners[j] = gltf_corner(j);
      if (std::abs(v.weights[j]) > kOnEdge) key[j] = v.corners[j];
    }
    std::sort(key.begin(), key.end());
    const auto [it, added] = ids_.try_emplace({w, key[0], key[1], key[2]}, 0);
    if (added) {
      it->second = static_cast<std::uint32_t>(gltf_.mesh_vertex.size() + added_.size());
      added_.push_back(v);
      added_vertex_.push_back(w);
    }
    return it->second;
  }

  const std::vector<InterpolatedVertex>& added() const { return added_; }
  const std::vector<int>& added_mesh_vertex() const { return added_vertex_; }
  // Each added glTF vertex's position (its mesh vertex's).
  std::vector<Vec3> added_positions() const {
    std::vector<Vec3> out;
    out.reserve(added_vertex_.size());
    for (const int w : added_vertex_) out.push_back(refinement_.mesh.vertices[w]);
    return out;
  }

 private:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFU;
  static constexpr double kOnEdge = 1e-9;  // a weight below this (rounding) does not make a corner part of the key

  // New vertex w's barycentric weights in input face s: its own when it was placed in s, else its weights on its own
  // face's corners moved to the same vertices of s (it lies on their shared edge), else the projection of its position.
  Barycentric weights_in(int w, int s) const {
    const SurfacePoint& p = refinement_.new_vertices[w - input_vertices_];
    const Face& face = gltf_.mesh.faces[s];
    if (p.face == s) return p.barycentric;
    Barycentric b{0.0, 0.0, 0.0};
    double lost = 0.0;
    for (int j = 0; j < 3; ++j) {
      const int vertex = gltf_.mesh.faces[p.face][j];
      const auto* at = std::find(face.begin(), face.end(), vertex);
      if (at == face.end()) {
        lost += std::abs(p.barycentric[j]);
      } else {
        b[at - face.begin()] += p.barycentric[j];
      }
    }
    if (lost <= kOnEdge) return b;
    return closest_point_on_triangle(refinement_.mesh.vertices[w], gltf_.mesh.vertices[face[0]],
                                     gltf_.mesh.vertices[face[1]], gltf_.mesh.vertices[face[2]])
        .barycentric;
  }

  const GltfMesh& gltf_;
  const MeshRefinement& refinement_;
  int input_vertices_;
  std::map<std::array<std::int64_t, 4>, std::uint32_t> ids_;  // (mesh vertex, glTF corners) → glTF vertex
  std::vector<InterpolatedVertex> added_;
  std::vector<int> added_vertex_;
};

// An attribute's values for the refined vertices: the input's (`input`, decoded), then each new vertex's: interpolated
// on its input triangle, or its nearest corner's (GltfAttribute::interpolated). The primitive's POSITION is the new
// vertex's own position (bit-equal in every glTF vertex of it); NORMAL and TANGENT's direction are renormalised (the
// nearest corner's where the corners' cancel), TANGENT's w (handedness) is the nearest corner's.
std::vector<float> refined_values(const GltfAttribute& a, const std::vector<float>& input,
                                  const std::vector<InterpolatedVertex>& added, const std::vector<Vec3>& positions) {
  const std::size_t c = a.components;
  std::vector<float> out = input;
  out.reserve(out.size() + added.size() * c);
  const bool unit = a.target < 0 && (a.name == "NORMAL" || a.name == "TANGENT");
  const bool position = a.target < 0 && a.name == "POSITION" && c == 3;
  for (std::size_t n = 0; n < added.size(); ++n) {
    const InterpolatedVertex& v = added[n];
    const std::size_t at = out.size();
    const std::size_t nearest = v.corners[v.nearest()];
    for (std::size_t k = 0; k < c; ++k) {
      double x = 0.0;
      if (!a.interpolated()) {
        x = input[nearest * c + k];
      } else {
        for (int j = 0; j < 3; ++j) x += v.weights[j] * input[v.corners[j] * c + k];
      }
      out.push_back(static_cast<float>(x));
    }
    if (position) {
      out[at] = static_cast<float>(positions[n].x);
      out[at + 1] = static_cast<float>(positions[n].y);
      out[at + 2] = static_cast<float>(positions[n].z);
    }
    if (unit && c >= 3) {
      const double length =
          std::sqrt(double(out[at]) * out[at] + double(out[at + 1]) * out[at + 1] + double(out[at + 2]) * out[at + 2]);
      for (std::size_t k = 0; k < 3; ++k) {
        out[at + k] = length > 1e-6 ? static_cast<float>(out[at + k] / length) : input[nearest * c + k];
      }
      if (c == 4) out[at + 3] = input[nearest * c + 3];
    }
  }
  return out;
}

// The accessor of an attribute's refined values: float where interpolated, the input's integer type otherwise.
std::size_t attribute_accessor(DataSink& sink, const GltfAttribute& a, const std::vector<float>& values) {
  const std::size_t count = values.size() / a.components;
  // Interpolated values and normalized integers as float (allowed for every semantic); integers as they were.
  const int type = a.interpolated() || a.normalized ? kGltfFloat : a.component_type;
  const int bytes = gltf_component_bytes(type);
  const int element = bytes * a.components;
  const int stride = (element + 3) / 4 * 4;  // vertex attributes' elements are 4-byte aligned
  std::string data;
  data.reserve(count * stride);
  for (std::size_t i = 0; i < count; ++i) {
    for (int k = 0; k < a.components; ++k) {
      const float x = values[i * a.components + k];
      switch (type) {
        case kGltfFloat:
          append_value(data, x);
          break;
        case TINYGLTF_COMPONENT_TYPE_BYTE:
          append_value(data, static_cast<std::int8_t>(x));
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
          append_value(data, static_cast<std::uint8_t>(x));
          break;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
          append_value(data, static_cast<std::int16_t>(x));
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
          append_value(data, static_cast<std::uint16_t>(x));
          break;
        default:
          append_value(data, static_cast<std::uint32_t>(x));
      }
    }
    data.append(static_cast<std::size_t>(stride - element), '\0');
  }
  nlohmann::json accessor = {{"componentType", type},
                             {"count", count},
                             {"type", element_type(a.components)},
                             {"name", "texwarp " + a.name}};
  if (a.name == "POSITION") {  // required for positions (and morph targets' positions)
    std::vector<float> lo(a.components, std::numeric_limits<float>::infinity());
    std::vector<float> hi(a.components, -std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < values.size(); ++i) {
      lo[i % a.components] = std::min(lo[i % a.components], values[i]);
      hi[i % a.components] = std::max(hi[i % a.components], values[i]);
    }
    accessor["min"] = lo;
    accessor["max"] = hi;
  }
  return sink.accessor(data, TINYGLTF_TARGET_ARRAY_BUFFER, stride == element ? 0 : stride, std::move(accessor));
}

}  // namespace

std::string textured_gltf_bytes(const GltfMesh& gltf, const MeshRegion& region,
                                std::span<const std::array<double, 2>> uvs,
                                const std::optional<std::string>& base_color_uri, const MeshRefinement* refinement) {
  if (refinement != nullptr && !gltf.unrefinable.empty()) {
    throw std::invalid_argument("textured_gltf_bytes: this glTF primitive cannot take new vertices: " +
                                gltf.unrefinable);
  }
  const TriangleMesh& out_mesh = refinement != nullptr ? refinement->mesh : gltf.mesh;
  // Every output face's glTF vertices (the input's corners unless refined).
  std::vector<std::uint32_t> corners;
  std::optional<RefinedVertices> refined;
  if (refinement != nullptr) {
    refined.emplace(gltf, *refinement);
    corners.resize(3 * static_cast<std::size_t>(out_mesh.face_count()));
    for (int f = 0; f < out_mesh.face_count(); ++f) {
      for (int k = 0; k < 3; ++k) corners[3 * static_cast<std::size_t>(f) + k] = refined->corner(f, k);
    }
  }
  const std::vector<std::uint32_t>& face_corners = refinement != nullptr ? corners : gltf.corners;

  std::vector<std::array<double, 2>> texcoord = gltf.texcoord0;
  if (refined) {
    // A new glTF vertex no region face uses (a face outside across a split boundary edge, on the other side of a UV
    // seam) keeps the outside's own UVs, interpolated as its other attributes are; the region's overwrite the rest.
    for (const InterpolatedVertex& v : refined->added()) {
      std::array<double, 2> uv{0.0, 0.0};
      for (int j = 0; j < 3; ++j) {
        uv[0] += v.weights[j] * gltf.texcoord0[v.corners[j]][0];
        uv[1] += v.weights[j] * gltf.texcoord0[v.corners[j]][1];
      }
      texcoord.push_back(uv);
    }
  }
  for (const int f : region.faces) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = face_corners[3 * static_cast<std::size_t>(f) + k];
      texcoord[v] = uvs[region.local_vertex[out_mesh.faces[f][k]]];
    }
  }
  std::string data;
  data.reserve(texcoord.size() * 8);
  for (const auto& uv : texcoord) {
    append_value(data, static_cast<float>(uv[0]));
    append_value(data, static_cast<float>(uv[1]));
  }

  nlohmann::json doc = gltf.document;
  DataSink sink(doc, gltf);
  const std::size_t uv_accessor = sink.accessor(
      data, TINYGLTF_TARGET_ARRAY_BUFFER, 0,
      {{"componentType", kGltfFloat}, {"count", texcoord.size()}, {"type", "VEC2"}, {"name", "texwarp TEXCOORD_0"}});
  nlohmann::json& primitive = doc["meshes"][gltf.mesh_index]["primitives"][gltf.primitive_index];
  primitive["attributes"]["TEXCOORD_0"] = uv_accessor;
  if (refined) {
    const std::map<int, std::vector<float>> decoded = decode_gltf_attributes(gltf);
    const std::vector<Vec3> positions = refined->added_positions();
    for (const GltfAttribute& a : gltf.attributes) {
      const std::size_t index =
          attribute_accessor(sink, a, refined_values(a, decoded.at(a.accessor), refined->added(), positions));
      if (a.target < 0) {
        primitive["attributes"][a.name] = index;
      } else {
        primitive["targets"][a.target][a.name] = index;
      }
    }
    std::string indices;
    indices.reserve(4 * corners.size());
    for (const std::uint32_t c : corners) append_value(indices, c);
    primitive["indices"] = sink.accessor(indices, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER, 0,
                                         {{"componentType", TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                                          {"count", corners.size()},
                                          {"type", "SCALAR"},
                                          {"name", "texwarp indices"}});
  }

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
  std::string bin = sink.finish();
  if (gltf.binary) return glb_container(doc, std::move(bin));
  return doc.dump(2) + "\n";
}

}  // namespace texwarp::mesh
