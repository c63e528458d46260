// glTF 2.0 input: see gltf_mesh.hpp. tinygltf parses the document and decodes the buffers; every accessor read here
// is range-checked against its buffer view and buffer before a byte is touched.
#include "texwarp/mesh/gltf_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <map>
#include <stdexcept>

#include "texwarp/mesh/tiny_gltf.hpp"

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::mesh {

static_assert(kGltfFloat == TINYGLTF_COMPONENT_TYPE_FLOAT);

int gltf_component_bytes(int component_type) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
      return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      return 4;
    default:
      return 0;
  }
}

namespace {

constexpr std::uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kGlbJsonChunk = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kGlbBinChunk = 0x004E4942;   // "BIN\0"

std::uint32_t read_u32(std::string_view bytes, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, bytes.data() + at, 4);  // glb is little-endian, as is every machine texwarp builds for
  return v;
}

struct GlbChunks {
  std::string_view json;
  std::string_view bin;
};

// The .glb container (12-byte header, a JSON chunk, an optional BIN chunk), checked strictly.
GlbChunks split_glb(std::string_view bytes, const InputLocation& where) {
  const auto bad = [&](const std::string& what) { throw InputError(where, "not a valid .glb file: " + what); };
  if (bytes.size() < 20) bad("shorter than a header and a chunk header (20 bytes)");
  if (read_u32(bytes, 0) != kGlbMagic) bad("it does not start with the magic \"glTF\"");
  if (read_u32(bytes, 4) != 2) bad("container version " + std::to_string(read_u32(bytes, 4)) + ", expected 2");
  if (read_u32(bytes, 8) != bytes.size()) {
    bad("the header says " + std::to_string(read_u32(bytes, 8)) + " bytes, the file has " +
        std::to_string(bytes.size()));
  }
  GlbChunks chunks;
  std::size_t at = 12;
  for (int k = 0; at < bytes.size(); ++k) {
    if (bytes.size() - at < 8) bad("chunk " + std::to_string(k) + " at byte " + std::to_string(at) + " is truncated");
    const std::size_t length = read_u32(bytes, at);
    const std::uint32_t type = read_u32(bytes, at + 4);
    if (length > bytes.size() - at - 8) {
      bad("chunk " + std::to_string(k) + " at byte " + std::to_string(at) + " claims " + std::to_string(length) +
          " bytes, past the end of the file");
    }
    const std::string_view payload = bytes.substr(at + 8, length);
    if (k == 0 && type != kGlbJsonChunk) bad("the first chunk is not JSON");
    if (k == 0) chunks.json = payload;
    if (k == 1 && type == kGlbBinChunk) chunks.bin = payload;
    at += 8 + length;
  }
  return chunks;
}

bool is_data_uri(const std::string& uri) { return uri.rfind("data:", 0) == 0; }

// Images are never decoded (texwarp only reads geometry): tinygltf keeps their URIs and buffer views.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

// An accessor's elements, checked to lie inside its buffer view and buffer.
struct AccessorView {
  const unsigned char* base = nullptr;
  std::size_t stride = 0;
  std::size_t count = 0;
  int component_type = 0;
  int components = 0;
  bool normalized = false;
  const unsigned char* element(std::size_t i) const { return base + i * stride; }
};

class PrimitiveReader {
 public:
  PrimitiveReader(const tinygltf::Model& model, std::string prefix, const InputLocation& where)
      : model_(model), prefix_(std::move(prefix)), where_(where) {}

  [[noreturn]] void fail(const std::string& what) const { throw InputError(where_, prefix_ + what); }

  AccessorView view(int index, const std::string& role) const {
    const std::string name = "accessor " + std::to_string(index) + " (" + role + ")";
    if (index < 0 || static_cast<std::size_t>(index) >= model_.accessors.size()) {
      fail(name + " does not exist (the file has " + std::to_string(model_.accessors.size()) + " accessors)");
    }
    const tinygltf::Accessor& a = model_.accessors[index];
    if (a.sparse.isSparse) fail(name + " is sparse: sparse accessors are not supported");
    if (a.bufferView < 0 || static_cast<std::size_t>(a.bufferView) >= model_.bufferViews.size()) {
      fail(name + " has no buffer view in range (bufferView " + std::to_string(a.bufferView) + ")");
    }
    const tinygltf::BufferView& bv = model_.bufferViews[a.bufferView];
    const std::string bv_name = "buffer view " + std::to_string(a.bufferView) + " of " + name;
    if (bv.buffer < 0 || static_cast<std::size_t>(bv.buffer) >= model_.buffers.size()) {
      fail(bv_name + " refers to buffer " + std::to_string(bv.buffer) + ", which does not exist");
    }
    const std::size_t buffer_size = model_.buffers[bv.buffer].data.size();
    if (bv.byteOffset > buffer_size || bv.byteLength > buffer_size - bv.byteOffset) {
      fail(bv_name + " (bytes " + std::to_string(bv.byteOffset) + " + " + std::to_string(bv.byteLength) +
           ") lies outside buffer " + std::to_string(bv.buffer) + " (" + std::to_string(buffer_size) + " bytes)");
    }
    AccessorView v;
    v.component_type = a.componentType;
    v.components = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type));
    v.normalized = a.normalized;
    const int cb = gltf_component_bytes(a.componentType);
    if (cb == 0 || v.components <= 0) fail(name + " has an unknown component type or element type");
    const std::size_t element_bytes = static_cast<std::size_t>(cb) * static_cast<std::size_t>(v.components);
    v.stride = bv.byteStride == 0 ? element_bytes : bv.byteStride;
    if (v.stride < element_bytes || v.stride > 252) {
      fail(bv_name + " has byteStride " + std::to_string(bv.byteStride) + ": expected " +
           std::to_string(element_bytes) + " to 252 for its " + std::to_string(element_bytes) + "-byte elements");
    }
    if (a.count == 0 || static_cast<long long>(a.count) > kMaxGltfElements) {
      fail(name + " has count " + std::to_string(a.count) + " (expected 1 to " + std::to_string(kMaxGltfElements) +
           ")");
    }
    v.count = a.count;
    const std::uint64_t end =
        static_cast<std::uint64_t>(a.byteOffset) + static_cast<std::uint64_t>(v.stride) * (v.count - 1) + element_bytes;
    if (end > bv.byteLength) {
      fail(name + ": " + std::to_string(v.count) + " elements from byte " + std::to_string(a.byteOffset) +
           " with stride " + std::to_string(v.stride) + " need " + std::to_string(end) + " bytes, its " + bv_name +
           " has " + std::to_string(bv.byteLength));
    }
    v.base = model_.buffers[bv.buffer].data.data() + bv.byteOffset + a.byteOffset;
    return v;
  }

 private:
  const tinygltf::Model& model_;
  std::string prefix_;
  const InputLocation& where_;
};

float read_float(const unsigned char* p) {
  float f = 0.0F;
  std::memcpy(&f, p, 4);
  return f;
}

std::uint32_t read_index(const AccessorView& v, std::size_t i) {
  const unsigned char* p = v.element(i);
  switch (v.component_type) {
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return *p;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t s = 0;
      std::memcpy(&s, p, 2);
      return s;
    }
    default: {
      std::uint32_t u = 0;
      std::memcpy(&u, p, 4);
      return u;
    }
  }
}

// Element i's components: normalized integers to [0, 1] or [−1, 1] (glTF's rules), others as they are; as float for
// the attributes a refinement interpolates, as double for TEXCOORD_0.
template <typename T>
void read_components(const AccessorView& v, std::size_t i, T* out) {
  const int bytes = gltf_component_bytes(v.component_type);
  for (int k = 0; k < v.components; ++k) {
    const unsigned char* p = v.element(i) + static_cast<std::ptrdiff_t>(k) * bytes;
    double x = 0.0;
    switch (v.component_type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        out[k] = static_cast<T>(read_float(p));
        continue;
      case TINYGLTF_COMPONENT_TYPE_BYTE: {
        std::int8_t c = 0;
        std::memcpy(&c, p, 1);
        x = v.normalized ? std::max(c / 127.0, -1.0) : c;
        break;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        x = v.normalized ? *p / 255.0 : *p;
        break;
      case TINYGLTF_COMPONENT_TYPE_SHORT: {
        std::int16_t c = 0;
        std::memcpy(&c, p, 2);
        x = v.normalized ? std::max(c / 32767.0, -1.0) : c;
        break;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        std::uint16_t c = 0;
        std::memcpy(&c, p, 2);
        x = v.normalized ? c / 65535.0 : c;
        break;
      }
      default: {
        std::uint32_t c = 0;
        std::memcpy(&c, p, 4);
        x = c;
      }
    }
    out[k] = static_cast<T>(x);
  }
}

// Every vertex attribute of the primitive and of its morph targets but TEXCOORD_0, described; or, in `unrefinable`, why
// new vertices could not be written (the file is still read: only refinement needs them). Nothing is decoded here.
void describe_attributes(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                         const PrimitiveReader& reader, std::size_t vertex_count, GltfMesh& out) {
  // Draco on the primitive, meshopt on a buffer view of one of its attributes (other primitives may be plain).
  if (primitive.extensions.count("KHR_draco_mesh_compression") > 0) {
    out.unrefinable = "its vertex data is compressed (KHR_draco_mesh_compression)";
    return;
  }
  const auto meshopt = [&](int accessor) {
    if (accessor < 0 || static_cast<std::size_t>(accessor) >= model.accessors.size()) return false;
    const int view = model.accessors[accessor].bufferView;
    return view >= 0 && static_cast<std::size_t>(view) < model.bufferViews.size() &&
           model.bufferViews[view].extensions.count("EXT_meshopt_compression") > 0;
  };
  bool compressed = std::any_of(primitive.attributes.begin(), primitive.attributes.end(),
                                [&](const auto& attribute) { return meshopt(attribute.second); });
  for (const auto& target : primitive.targets) {
    compressed = compressed || std::any_of(target.begin(), target.end(),
                                           [&](const auto& attribute) { return meshopt(attribute.second); });
  }
  if (compressed) {
    out.unrefinable = "its vertex data is compressed (EXT_meshopt_compression)";
    return;
  }
  std::map<int, std::uint64_t> distinct;  // accessor → its decoded bytes
  const auto add = [&](const std::string& name, int accessor, int target) {
    const std::string role = target < 0 ? name : "morph target " + std::to_string(target) + " " + name;
    AccessorView v;
    try {
      v = reader.view(accessor, role);
    } catch (const InputError& e) {
      out.unrefinable = e.detail();
      return false;
    }
    if (v.count != vertex_count) {
      out.unrefinable =
          role + " has " + std::to_string(v.count) + " elements, POSITION " + std::to_string(vertex_count);
      return false;
    }
    const int type = model.accessors[accessor].type;
    if (type != TINYGLTF_TYPE_SCALAR && type != TINYGLTF_TYPE_VEC2 && type != TINYGLTF_TYPE_VEC3 &&
        type != TINYGLTF_TYPE_VEC4) {
      out.unrefinable = role + " is a matrix";
      return false;
    }
    if (v.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
      out.unrefinable = role + " is unsigned int, which glTF does not allow for vertex attributes";
      return false;
    }
    GltfAttribute a;
    a.name = name;
    a.target = target;
    a.accessor = accessor;
    a.component_type = v.component_type;
    a.normalized = v.normalized;
    a.components = v.components;
    distinct[accessor] = static_cast<std::uint64_t>(v.count) * static_cast<std::uint64_t>(v.components) * 4;
    out.attributes.push_back(std::move(a));
    return true;
  };
  for (const auto& [name, accessor] : primitive.attributes) {
    if (name != "TEXCOORD_0" && !add(name, accessor, -1)) return;
  }
  for (std::size_t t = 0; t < primitive.targets.size(); ++t) {
    for (const auto& [name, accessor] : primitive.targets[t]) {
      if (!add(name, accessor, static_cast<int>(t))) return;
    }
  }
  for (const auto& [accessor, bytes] : distinct) out.refinement_bytes += 2 * bytes;
}

std::string mesh_label(const tinygltf::Model& model, int index) {
  const std::string& name = model.meshes[index].name;
  return "mesh " + std::to_string(index) + (name.empty() ? "" : " (" + proto::quoted_key(name) + ")");
}

int select_mesh(const tinygltf::Model& model, const proto::GltfSelectionSpec& selection, const InputLocation& where) {
  if (model.meshes.empty()) throw InputError(where, "the glTF file has no meshes");
  if (selection.mesh_name) {
    std::string names;
    for (std::size_t i = 0; i < model.meshes.size(); ++i) {
      if (model.meshes[i].name == *selection.mesh_name) return static_cast<int>(i);
      if (i < 20) names += (names.empty() ? "" : ", ") + proto::quoted_key(model.meshes[i].name);
    }
    throw InputError(where, "the glTF file has no mesh named " + proto::quoted_key(*selection.mesh_name) +
                                " (its meshes: " + names + (model.meshes.size() > 20 ? ", …" : "") + ")");
  }
  const int index = selection.mesh_index.value_or(0);
  if (static_cast<std::size_t>(index) >= model.meshes.size()) {
    throw InputError(where, "mesh " + std::to_string(index) + " does not exist (the glTF file has " +
                                std::to_string(model.meshes.size()) + " meshes)");
  }
  return index;
}

}  // namespace

GltfMesh parse_gltf_mesh(std::string_view bytes, bool binary, const proto::GltfSelectionSpec& selection,
                         const InputLocation& where) {
  GltfMesh out;
  out.binary = binary;
  std::string_view json_text = bytes;
  if (binary) {
    const GlbChunks chunks = split_glb(bytes, where);
    json_text = chunks.json;
    out.binary_chunk = std::string(chunks.bin);
  }
  try {
    out.document = proto::parse_json(json_text, "glTF JSON");
  } catch (const InputError& e) {
    throw InputError(where, e.what());
  }
  if (!out.document.is_object()) throw InputError(where, "not a glTF file: its JSON is not an object");
  // Only embedded buffers are read: a URI naming a file would make the server open paths chosen by the sender.
  if (const auto it = out.document.find("buffers"); it != out.document.end() && it->is_array()) {
    for (std::size_t i = 0; i < it->size(); ++i) {
      const auto& b = (*it)[i];
      if (b.is_object() && b.contains("uri") && b["uri"].is_string() && !is_data_uri(b["uri"].get<std::string>())) {
        throw InputError(where, "buffer " + std::to_string(i) + " refers to the external file " +
                                    proto::quoted_key(b["uri"].get<std::string>()) +
                                    ", which is not read: embed the buffers (.glb, or glTF with data: URIs)");
      }
    }
  }

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&skip_image, nullptr);
  tinygltf::Model model;
  std::string error;
  std::string warning;
  const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &error, &warning,
                                                       reinterpret_cast<const unsigned char*>(bytes.data()),
                                                       static_cast<unsigned int>(bytes.size()), "")
                         : loader.LoadASCIIFromString(&model, &error, &warning, json_text.data(),
                                                      static_cast<unsigned int>(json_text.size()), "");
  if (!ok) {
    while (!error.empty() && (error.back() == '\n' || error.back() == '\r')) error.pop_back();
    throw InputError(where, "not a valid glTF 2.0 file: " + (error.empty() ? std::string("parse error") : error));
  }
  if (model.asset.version.rfind("2.", 0) != 0) {
    throw InputError(where, "asset.version is " + proto::quoted_key(model.asset.version) + ": only glTF 2.x is read");
  }

  out.mesh_index = select_mesh(model, selection, where);
  const tinygltf::Mesh& mesh = model.meshes[out.mesh_index];
  const std::string label = mesh_label(model, out.mesh_index);
  if (static_cast<std::size_t>(selection.primitive) >= mesh.primitives.size()) {
    throw InputError(where, "primitive " + std::to_string(selection.primitive) + " does not exist (" + label + " has " +
                                std::to_string(mesh.primitives.size()) + " primitives)");
  }
  out.primitive_index = selection.primitive;
  const tinygltf::Primitive& primitive = mesh.primitives[out.primitive_index];
  const PrimitiveReader reader(model, label + " primitive " + std::to_string(out.primitive_index) + ": ", where);
  if (primitive.mode != -1 && primitive.mode != TINYGLTF_MODE_TRIANGLES) {
    reader.fail("mode " + std::to_string(primitive.mode) +
                " is not triangles (4): points, lines, strips and fans are not read");
  }
  const auto position = primitive.attributes.find("POSITION");
  if (position == primitive.attributes.end()) reader.fail("it has no POSITION attribute");
  const AccessorView positions = reader.view(position->second, "POSITION");
  if (positions.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT || positions.components != 3) {
    reader.fail("POSITION must be float VEC3 (quantized positions are not supported)");
  }
  std::vector<std::uint32_t> corners;
  if (primitive.indices >= 0) {
    const AccessorView indices = reader.view(primitive.indices, "indices");
    if (indices.components != 1 || (indices.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                    indices.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                                    indices.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)) {
      reader.fail("indices must be unsigned byte, short or int SCALARs");
    }
    corners.resize(indices.count);
    for (std::size_t i = 0; i < indices.count; ++i) {
      corners[i] = read_index(indices, i);
      if (corners[i] >= positions.count) {
        reader.fail("index " + std::to_string(i) + " is " + std::to_string(corners[i]) + ", past the " +
                    std::to_string(positions.count) + " POSITION elements");
      }
    }
  } else {
    corners.resize(positions.count);
    for (std::size_t i = 0; i < positions.count; ++i) corners[i] = static_cast<std::uint32_t>(i);
  }
  if (corners.size() % 3 != 0) {
    reader.fail(std::to_string(corners.size()) + " triangle corners, not a multiple of 3");
  }
  out.texcoord0.assign(positions.count, {0.0, 0.0});
  if (const auto tc = primitive.attributes.find("TEXCOORD_0"); tc != primitive.attributes.end()) {
    const AccessorView uv = reader.view(tc->second, "TEXCOORD_0");
    if (uv.components != 2 || uv.count != positions.count ||
        !(uv.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT ||
          (uv.normalized && (uv.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                             uv.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)))) {
      reader.fail("TEXCOORD_0 must be VEC2 (float or normalized unsigned byte/short) with one element per "
                  "POSITION element");
    }
    for (std::size_t i = 0; i < uv.count; ++i) read_components(uv, i, out.texcoord0[i].data());
  }

  // Weld: one mesh vertex per distinct position used by a triangle, in glTF vertex order.
  std::vector<char> used(positions.count, 0);
  for (const std::uint32_t c : corners) used[c] = 1;
  out.mesh_vertex.assign(positions.count, -1);
  std::map<std::array<float, 3>, int> by_position;
  for (std::size_t i = 0; i < positions.count; ++i) {
    if (!used[i]) continue;
    const unsigned char* p = positions.element(i);
    const std::array<float, 3> xyz{read_float(p), read_float(p + 4), read_float(p + 8)};
    if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
      reader.fail("POSITION element " + std::to_string(i) + " is not finite");
    }
    const auto [it, added] = by_position.try_emplace(xyz, out.mesh.vertex_count());
    if (added) out.mesh.vertices.push_back({xyz[0], xyz[1], xyz[2]});
    out.mesh_vertex[i] = it->second;
  }
  out.mesh.faces.reserve(corners.size() / 3);
  for (std::size_t t = 0; t < corners.size(); t += 3) {
    out.mesh.faces.push_back(
        {out.mesh_vertex[corners[t]], out.mesh_vertex[corners[t + 1]], out.mesh_vertex[corners[t + 2]]});
  }
  out.corners = std::move(corners);
  describe_attributes(model, primitive, reader, positions.count, out);
  if (!out.unrefinable.empty()) {
    out.attributes.clear();
    out.refinement_bytes = 0;
  }
  out.held_bytes = 3 * static_cast<std::uint64_t>(json_text.size()) + out.binary_chunk.size() +
                   out.corners.size() * sizeof(std::uint32_t) +
                   out.mesh_vertex.size() * (sizeof(int) + sizeof(std::array<double, 2>));
  return out;
}

std::map<int, std::vector<float>> decode_gltf_attributes(const GltfMesh& gltf) {
  const std::string bytes = gltf.binary ? glb_container(gltf.document, gltf.binary_chunk) : gltf.document.dump();
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&skip_image, nullptr);
  tinygltf::Model model;
  std::string error;
  std::string warning;
  const bool ok = gltf.binary ? loader.LoadBinaryFromMemory(&model, &error, &warning,
                                                            reinterpret_cast<const unsigned char*>(bytes.data()),
                                                            static_cast<unsigned int>(bytes.size()), "")
                              : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(),
                                                           static_cast<unsigned int>(bytes.size()), "");
  if (!ok) throw std::runtime_error("glTF: the document read before could not be read again: " + error);
  const InputLocation where;
  const PrimitiveReader reader(model, "", where);
  std::map<int, std::vector<float>> values;
  for (const GltfAttribute& a : gltf.attributes) {
    if (values.count(a.accessor) > 0) continue;
    const AccessorView v = reader.view(a.accessor, a.name);
    std::vector<float>& out = values[a.accessor];
    out.resize(v.count * static_cast<std::size_t>(v.components));
    for (std::size_t i = 0; i < v.count; ++i) read_components(v, i, out.data() + i * v.components);
  }
  return values;
}

std::string glb_container(const nlohmann::json& json, std::string bin) {
  std::string text = json.dump();
  while (text.size() % 4 != 0) text.push_back(' ');
  while (bin.size() % 4 != 0) bin.push_back('\0');
  const std::uint64_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size());
  if (total > 0xFFFFFFFFULL) {
    throw std::length_error("the .glb would be " + std::to_string(total) + " bytes, past glTF's 4 GiB");
  }
  std::string out;
  out.reserve(total);
  const auto put_u32 = [&out](std::uint32_t v) {
    char b[4];
    std::memcpy(b, &v, 4);
    out.append(b, 4);
  };
  put_u32(kGlbMagic);
  put_u32(2);
  put_u32(static_cast<std::uint32_t>(total));
  put_u32(static_cast<std::uint32_t>(text.size()));
  put_u32(kGlbJsonChunk);
  out += text;
  if (!bin.empty()) {
    put_u32(static_cast<std::uint32_t>(bin.size()));
    put_u32(kGlbBinChunk);
    out += bin;
  }
  return out;
}

}  // namespace texwarp::mesh
