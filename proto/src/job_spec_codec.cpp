// JSON codec for jobs: see job_spec_codec.hpp.
#include "texwarp/proto/job_spec_codec.hpp"

#include <algorithm>
#include <array>
#include <initializer_list>

#include "texwarp/proto/base64.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_labels_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/mesh_spec_codec.hpp"
#include "texwarp/proto/udim_tiles.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"

namespace texwarp::proto {
namespace {

constexpr long long kMaxId = 0x7fffffffLL;  // largest 0-based id (an int)

// An optional string key whose value must name one of E's values.
template <WireEnum E>
std::optional<E> optional_enum(JsonReader& r, std::string_view key) {
  const auto value = r.optional_string(key);
  if (!value) return std::nullopt;
  return parse_enum<E>(*value, r.key_path(key));
}

// Exactly one of `keys` must be present; returns it.
std::string exactly_one_of(JsonReader& r, std::initializer_list<const char*> keys) {
  std::string names;
  for (const char* k : keys) names += (names.empty() ? "\"" : ", \"") + std::string(k) + "\"";
  std::string found;
  for (const char* k : keys) {
    if (!r.has(k)) continue;
    if (!found.empty()) {
      std::string message = "give exactly one of " + names;
      message.append(R"( (")").append(found).append(R"(" is given too))");
      throw InputError(r.key_path(k), message);
    }
    found = k;
  }
  if (found.empty()) {
    for (const char* k : keys) {
      if (const auto near = r.near_unknown_key(k)) {
        throw InputError(r.path(),
                         "expected exactly one of " + names + " (there is an unknown key " + quoted_key(*near) + ")");
      }
    }
    throw InputError(r.path(), "expected exactly one of " + names);
  }
  return found;
}

std::string required_string(JsonReader& r, std::string_view key) {
  const auto& v = r.at(key);
  if (!v.is_string()) throw InputError(r.key_path(key), "expected a string, got " + json_type_name(v));
  return v.get<std::string>();
}

const nlohmann::json& required_object(JsonReader& r, std::string_view key) {
  const auto& v = r.at(key);
  if (!v.is_object()) throw InputError(r.key_path(key), "expected an object, got " + json_type_name(v));
  return v;
}

int output_side(JsonReader& r, std::string_view key) {
  const auto v = r.optional_integer(key);
  if (!v) return 0;
  if (*v < 1 || *v > kMaxOutputSide) {
    throw InputError(r.key_path(key),
                     "expected an integer from 1 to " + std::to_string(kMaxOutputSide) + ", got " + std::to_string(*v));
  }
  return static_cast<int>(*v);
}

std::string blob_id(JsonReader& r, std::string_view key) {
  std::string id = required_string(r, key);
  if (!is_blob_id(id)) {
    throw InputError(r.key_path(key), "expected a blob id \"sha256:<64 lowercase hex digits>\" (as POST /v1/blobs "
                                      "returns), got \"" +
                                          id.substr(0, 80) + "\"");
  }
  return id;
}

std::string nonempty_path(JsonReader& r, std::string_view key) {
  std::string p = required_string(r, key);
  if (p.empty()) throw InputError(r.key_path(key), "expected a file path, got an empty string");
  if (p.find('\0') != std::string::npos) throw InputError(r.key_path(key), "a path cannot contain a NUL character");
  return p;
}

// The keys of an image source (the source, role, colour space, convention) from `r`; the caller rejects the rest.
// "tiles": a UDIM texture's tiles one by one, [{"tile": 1001…1100, "blob" | "base64"}], each number once.
std::vector<UdimTileSource> decode_udim_tiles(const nlohmann::json& value, const JsonPath& path) {
  constexpr std::size_t kMaxTiles = kLastUdimTile - kFirstUdimTile + 1;
  if (!value.is_array()) throw InputError(path, "expected an array of UDIM tiles, got " + json_type_name(value));
  if (value.empty() || value.size() > kMaxTiles) {
    throw InputError(path, std::to_string(value.size()) + " tiles: a UDIM texture has 1 to " +
                               std::to_string(kMaxTiles) + " tiles (" + std::to_string(kFirstUdimTile) + "–" +
                               std::to_string(kLastUdimTile) + ")");
  }
  std::vector<UdimTileSource> tiles;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const JsonPath at = path.index(i);
    if (!value[i].is_object()) throw InputError(at, "expected an object, got " + json_type_name(value[i]));
    JsonReader r(value[i], at);
    UdimTileSource tile;
    const auto number = r.optional_integer("tile");
    if (!number)
      throw InputError(r.key_path("tile"), "required: the tile's number, " + std::to_string(kFirstUdimTile) + " to " +
                                               std::to_string(kLastUdimTile));
    if (*number < kFirstUdimTile || *number > kLastUdimTile) {
      throw InputError(r.key_path("tile"), "expected a UDIM tile number from " + std::to_string(kFirstUdimTile) +
                                               " to " + std::to_string(kLastUdimTile) + ", got " +
                                               std::to_string(*number));
    }
    tile.number = static_cast<int>(*number);
    if (exactly_one_of(r, {"blob", "base64"}) == "blob") {
      tile.blob = blob_id(r, "blob");
    } else {
      tile.data = base64_decode(required_string(r, "base64"), r.key_path("base64"));
      if (tile.data.empty()) throw InputError(r.key_path("base64"), "the inline tile is empty");
    }
    r.reject_unknown_keys();
    for (std::size_t j = 0; j < tiles.size(); ++j) {
      if (tiles[j].number == tile.number) {
        throw InputError(at.key("tile"), "tile " + std::to_string(tile.number) + " is given twice (tiles[" +
                                             std::to_string(j) + "] and tiles[" + std::to_string(i) + "])");
      }
    }
    tiles.push_back(std::move(tile));
  }
  return tiles;
}

ImageSourceSpec read_image_source(JsonReader& r) {
  ImageSourceSpec image;
  const std::string kind = exactly_one_of(r, {"blob", "base64", "path", "tiles"});
  if (kind == "blob") {
    image.kind = ImageSourceSpec::Kind::kBlob;
    image.blob = blob_id(r, "blob");
  } else if (kind == "base64") {
    image.kind = ImageSourceSpec::Kind::kBase64;
    image.data = base64_decode(required_string(r, "base64"), r.key_path("base64"));
    if (image.data.empty()) throw InputError(r.key_path("base64"), "the inline image is empty");
  } else if (kind == "tiles") {
    image.kind = ImageSourceSpec::Kind::kTiles;
    image.tiles = decode_udim_tiles(r.at("tiles"), r.key_path("tiles"));
  } else {
    image.kind = ImageSourceSpec::Kind::kPath;
    image.path = nonempty_path(r, "path");
  }
  image.role = optional_enum<ImageRole>(r, "role");
  if (auto name = r.optional_string("color_space")) {
    // sRGB's and linear's names are kept canonical; another is a space of OpenColorIO's config, which the job's
    // plan looks up (422 on submission when unknown).
    if (name->empty() || name->size() > kMaxColorSpaceNameBytes ||
        std::any_of(name->begin(), name->end(), [](char c) { return static_cast<unsigned char>(c) < 0x20; })) {
      throw InputError(r.key_path("color_space"), "expected a colour space's name of 1 to " +
                                                      std::to_string(kMaxColorSpaceNameBytes) +
                                                      " bytes without control characters");
    }
    image.color_space = canonical_color_space(*name).value_or(*name);
  }
  if (auto v = optional_enum<NormalConvention>(r, "normal_convention")) image.normal_convention = *v;
  return image;
}

ImageSourceSpec decode_image(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  ImageSourceSpec image = read_image_source(r);
  r.reject_unknown_keys();
  return image;
}

bool is_image_name(const std::string& name) {
  if (name.empty() || name.size() > kMaxImageNameLength || name.front() == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
           c == '-';
  });
}

// A path's file name without its extension and UDIM token: "maps/base_color.png" → "base_color",
// "maps/base_color.<UDIM>.exr" → "base_color".
std::string path_stem(const std::string& path) {
  const auto slash = path.find_last_of('/');
  std::string file = slash == std::string::npos ? path : path.substr(slash + 1);
  const auto dot = file.rfind('.');
  if (dot != std::string::npos && dot > 0) file.resize(dot);
  if (const auto at = file.find(kUdimToken); at != std::string::npos) {
    file.erase(at, std::string_view(kUdimToken).size());
    while (!file.empty() && (file.back() == '.' || file.back() == '_')) file.pop_back();
  }
  return file;
}

// "images": 1…kMaxJobImages entries {…source…, "name"}, names unique.
std::vector<NamedImageSpec> decode_images(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_array()) throw InputError(path, "expected an array of images, got " + json_type_name(value));
  if (value.empty() || value.size() > kMaxJobImages) {
    throw InputError(path, std::to_string(value.size()) + " images: a texture set has 1 to " +
                               std::to_string(kMaxJobImages) + " maps");
  }
  std::vector<NamedImageSpec> images;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const JsonPath at = path.index(i);
    if (!value[i].is_object()) throw InputError(at, "expected an object, got " + json_type_name(value[i]));
    JsonReader r(value[i], at);
    NamedImageSpec entry;
    entry.source = read_image_source(r);
    if (auto name = r.optional_string("name")) {
      entry.name = *name;
    } else if (entry.source.kind == ImageSourceSpec::Kind::kPath) {
      entry.name = path_stem(entry.source.path);
    } else {
      throw InputError(r.key_path("name"),
                       "required for a blob, base64 or tiles image: the name its output is written under");
    }
    if (!is_image_name(entry.name)) {
      throw InputError(
          r.has("name") ? r.key_path("name") : r.key_path("path"),
          "\"" + entry.name.substr(0, 120) + "\" is not an output name: 1 to " + std::to_string(kMaxImageNameLength) +
              " of A–Z, a–z, 0–9, '.', '_' and '-', not starting with '.'" + (r.has("name") ? "" : " (give \"name\")"));
    }
    r.reject_unknown_keys();
    for (std::size_t j = 0; j < images.size(); ++j) {
      if (images[j].name == entry.name) {
        throw InputError(at, "images " + std::to_string(j) + " and " + std::to_string(i) + " are both named \"" +
                                 entry.name + "\": each map's output needs its own name");
      }
    }
    images.push_back(std::move(entry));
  }
  return images;
}

// "gltf": {"mesh": name or index, "primitive": index}.
GltfSelectionSpec decode_gltf_selection(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  GltfSelectionSpec gltf;
  if (r.has("mesh")) {
    const nlohmann::json& mesh = r.at("mesh");
    if (mesh.is_string()) {
      gltf.mesh_name = mesh.get<std::string>();
    } else if (mesh.is_number_integer() && mesh.get<long long>() >= 0 && mesh.get<long long>() <= kMaxId) {
      gltf.mesh_index = static_cast<int>(mesh.get<long long>());
    } else {
      throw InputError(r.key_path("mesh"), "expected a mesh name (string) or a 0-based mesh index, got " +
                                               (mesh.is_number() ? mesh.dump() : json_type_name(mesh)));
    }
  }
  if (auto p = r.optional_integer("primitive")) {
    if (*p < 0 || *p > kMaxId) {
      throw InputError(r.key_path("primitive"), "expected a 0-based primitive index, got " + std::to_string(*p));
    }
    gltf.primitive = static_cast<int>(*p);
  }
  r.reject_unknown_keys();
  return gltf;
}

MeshSourceSpec decode_mesh_source(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  MeshSourceSpec source;
  const std::string kind = exactly_one_of(r, {"blob", "path", "inline", "obj"});
  const auto format = optional_enum<MeshFormat>(r, "format");
  if (format && (kind == "inline" || kind == "obj")) {
    throw InputError(r.key_path("format"), R"("format" only applies to a "blob" or "path" mesh)");
  }
  if (kind == "blob") {
    source.kind = MeshSourceSpec::Kind::kBlob;
    source.blob = blob_id(r, "blob");
    if (!format) throw InputError(r.key_path("format"), "required with \"blob\": " + quoted_enum_names<MeshFormat>());
    source.format = *format;
  } else if (kind == "path") {
    source.kind = MeshSourceSpec::Kind::kPath;
    source.path = nonempty_path(r, "path");
    if (format) {
      source.format = *format;
    } else {
      const auto dot = source.path.rfind('.');
      std::string ext = dot == std::string::npos ? "" : source.path.substr(dot + 1);
      std::transform(ext.begin(), ext.end(), ext.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      const auto from_extension = enum_from_name<MeshFormat>(ext);
      if (!from_extension) {
        throw InputError(r.key_path("path"), "cannot tell the mesh format from the extension: give \"format\": " +
                                                 quoted_enum_names<MeshFormat>());
      }
      source.format = *from_extension;
    }
  } else if (kind == "inline") {
    source.kind = MeshSourceSpec::Kind::kInline;
    source.mesh = decode_mesh_data(required_object(r, "inline"), r.key_path("inline"));
  } else {
    source.kind = MeshSourceSpec::Kind::kObjText;
    source.obj_text = required_string(r, "obj");
    if (source.obj_text.empty()) throw InputError(r.key_path("obj"), "the OBJ text is empty");
  }
  if (r.has("gltf")) {
    if ((kind != "blob" && kind != "path") ||
        (source.format != MeshFormat::kGltf && source.format != MeshFormat::kGlb)) {
      throw InputError(r.key_path("gltf"), R"("gltf" only applies to a glTF mesh ("format": "gltf" or "glb"))");
    }
    source.gltf = decode_gltf_selection(required_object(r, "gltf"), r.key_path("gltf"));
  }
  r.reject_unknown_keys();
  return source;
}

MeshJobSpec decode_mesh(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  MeshJobSpec mesh;
  mesh.source = decode_mesh_source(r.at("source"), r.key_path("source"));
  if (r.has("region")) mesh.region = decode_region_spec(required_object(r, "region"), r.key_path("region"));
  mesh.features = decode_surface_feature_set(required_object(r, "features"), r.key_path("features"));
  if (auto m = r.optional_number("margin_px")) {
    if (*m < 0.0) throw InputError(r.key_path("margin_px"), "expected a number ≥ 0, got " + std::to_string(*m));
    mesh.margin_px = *m;
  }
  if (auto uv = optional_enum<ObjUv>(r, "obj_uv")) mesh.obj_uv = *uv;
  if (auto b = r.optional_bool("per_triangle")) mesh.per_triangle = *b;
  if (auto b = r.optional_bool("per_vertex")) mesh.per_vertex = *b;
  r.reject_unknown_keys();
  return mesh;
}

OutputSpec decode_output(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  OutputSpec out;
  out.width = output_side(r, "width");
  out.height = output_side(r, "height");
  if (auto v = optional_enum<Interpolation>(r, "interpolation")) out.interpolation = *v;
  if (auto v = optional_enum<Border>(r, "border")) out.border = *v;
  if (auto v = optional_enum<SamplingFilter>(r, "filter")) out.filter = *v;
  out.pixel_format = optional_enum<PixelFormat>(r, "pixel_format");
  if (auto v = optional_enum<FileFormat>(r, "file_format")) out.file_format = *v;
  if (auto v = r.optional_bool("image")) out.image = *v;
  if (auto v = optional_enum<UvOrigin>(r, "uv_origin")) out.uv_origin = *v;
  if (auto v = r.optional_integer("png_compression_level")) {
    if (*v < 0 || *v > kMaxPngCompressionLevel) {
      throw InputError(r.key_path("png_compression_level"), "expected an integer from 0 to " +
                                                                std::to_string(kMaxPngCompressionLevel) + ", got " +
                                                                std::to_string(*v));
    }
    out.png_compression_level = static_cast<int>(*v);
  }
  if (auto v = optional_enum<Compression>(r, "compression")) out.compression = *v;
  if (auto v = r.optional_bool("texture")) {
    if (*v && out.file_format == FileFormat::kPng) {
      throw InputError(r.key_path("texture"), "a render-ready texture is a TIFF (.tx) or an EXR: give \"file_format\": "
                                              "\"tiff\" or \"exr\"");
    }
    out.texture = *v;
  }
  r.reject_unknown_keys();
  return out;
}

JobOptionsSpec decode_options(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  JobOptionsSpec options;
  if (auto v = r.optional_bool("exact")) options.exact = *v;
  if (auto v = r.optional_number("tolerance_px")) {
    if (*v < kMinLatticeTolerancePx || *v > kMaxLatticeTolerancePx) {
      throw InputError(r.key_path("tolerance_px"), "expected a number from " + std::to_string(kMinLatticeTolerancePx) +
                                                       " to " + std::to_string(kMaxLatticeTolerancePx) + " (pixels)");
    }
    options.tolerance_px = *v;
  }
  if (auto v = r.optional_string("device")) options.device = parse_device(*v, r.key_path("device"));
  if (auto v = r.optional_bool("jacobian_check")) options.jacobian_check = *v;
  if (auto v = r.optional_bool("refine")) options.refine = *v;
  if (auto v = optional_enum<UvOptimize>(r, "optimize")) options.optimize = *v;
  r.reject_unknown_keys();
  return options;
}

nlohmann::json encode_image_source(const ImageSourceSpec& image) {
  nlohmann::json j;
  switch (image.kind) {
    case ImageSourceSpec::Kind::kBlob:
      j = {{"blob", image.blob}};
      break;
    case ImageSourceSpec::Kind::kBase64:
      j = {{"base64", base64_encode(image.data)}};
      break;
    case ImageSourceSpec::Kind::kPath:
      j = {{"path", image.path}};
      break;
    case ImageSourceSpec::Kind::kTiles: {
      nlohmann::json tiles = nlohmann::json::array();
      for (const UdimTileSource& t : image.tiles) {
        if (t.blob.empty()) {
          tiles.push_back({{"tile", t.number}, {"base64", base64_encode(t.data)}});
        } else {
          tiles.push_back({{"tile", t.number}, {"blob", t.blob}});
        }
      }
      j = {{"tiles", std::move(tiles)}};
      break;
    }
  }
  if (image.role) j["role"] = to_string(*image.role);
  if (!image.color_space.empty()) j["color_space"] = image.color_space;
  j["normal_convention"] = to_string(image.normal_convention);
  return j;
}

}  // namespace

bool is_blob_id(const std::string& id) {
  constexpr std::string_view kPrefix = "sha256:";
  if (id.size() != kPrefix.size() + 64 || id.compare(0, kPrefix.size(), kPrefix) != 0) return false;
  return std::all_of(id.begin() + static_cast<std::ptrdiff_t>(kPrefix.size()), id.end(),
                     [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

JobSpec decode_job_spec(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  JobSpec spec;
  if (auto name = r.optional_string("name")) {
    if (name->size() > kMaxJobNameLength) {
      throw InputError(r.key_path("name"), "longer than " + std::to_string(kMaxJobNameLength) + " bytes");
    }
    if (has_control_characters(*name)) {
      throw InputError(r.key_path("name"),
                       "a job name is one line of text: no control characters (U+0000–U+001F, U+007F)");
    }
    spec.name = *name;
  }
  if (exactly_one_of(r, {"image", "images"}) == "image") {
    spec.image = decode_image(r.at("image"), r.key_path("image"));
  } else {
    spec.images = decode_images(r.at("images"), r.key_path("images"));
  }
  const std::string kind = exactly_one_of(r, {"warp", "mesh"});
  if (kind == "warp") {
    spec.warp = decode_warp_spec(r.at("warp"), r.key_path("warp"));
  } else {
    spec.mesh = decode_mesh(r.at("mesh"), r.key_path("mesh"));
  }
  if (r.has("output")) spec.output = decode_output(r.at("output"), r.key_path("output"));
  if (r.has("options")) spec.options = decode_options(r.at("options"), r.key_path("options"));
  if (auto v = r.optional_integer("priority")) {
    if (*v < kMinJobPriority || *v > kMaxJobPriority) {
      throw InputError(r.key_path("priority"), "expected an integer from " + std::to_string(kMinJobPriority) + " to " +
                                                   std::to_string(kMaxJobPriority) + ", got " + std::to_string(*v));
    }
    spec.priority = static_cast<int>(*v);
  }
  if (r.has("labels")) spec.labels = decode_job_labels(r.at("labels"), r.key_path("labels"));
  r.reject_unknown_keys();
  return spec;
}

nlohmann::json encode_job_spec(const JobSpec& spec) {
  nlohmann::json j = nlohmann::json::object();
  if (!spec.name.empty()) j["name"] = spec.name;
  if (spec.is_set()) {
    nlohmann::json images = nlohmann::json::array();
    for (const NamedImageSpec& entry : spec.images) {
      nlohmann::json e = encode_image_source(entry.source);
      e["name"] = entry.name;
      images.push_back(std::move(e));
    }
    j["images"] = std::move(images);
  } else {
    j["image"] = encode_image_source(spec.image);
  }
  if (spec.warp) j["warp"] = encode_warp_spec(*spec.warp);
  if (spec.mesh) {
    const MeshJobSpec& m = *spec.mesh;
    nlohmann::json source;
    const char* format = to_string(m.source.format);
    switch (m.source.kind) {
      case MeshSourceSpec::Kind::kBlob:
        source = {{"blob", m.source.blob}, {"format", format}};
        break;
      case MeshSourceSpec::Kind::kPath:
        source = {{"path", m.source.path}, {"format", format}};
        break;
      case MeshSourceSpec::Kind::kInline:
        source = {{"inline", encode_mesh_data(m.source.mesh)}};
        break;
      case MeshSourceSpec::Kind::kObjText:
        source = {{"obj", m.source.obj_text}};
        break;
    }
    if (m.source.gltf) {
      nlohmann::json gltf = {{"primitive", m.source.gltf->primitive}};
      if (m.source.gltf->mesh_name) gltf["mesh"] = *m.source.gltf->mesh_name;
      if (m.source.gltf->mesh_index) gltf["mesh"] = *m.source.gltf->mesh_index;
      source["gltf"] = std::move(gltf);
    }
    nlohmann::json mesh = {{"source", std::move(source)},    {"features", encode_surface_feature_set(m.features)},
                           {"margin_px", m.margin_px},       {"obj_uv", to_string(m.obj_uv)},
                           {"per_triangle", m.per_triangle}, {"per_vertex", m.per_vertex}};
    if (m.region) mesh["region"] = encode_region_spec(*m.region);
    j["mesh"] = std::move(mesh);
  }
  nlohmann::json output = {{"interpolation", to_string(spec.output.interpolation)},
                           {"border", to_string(spec.output.border)},
                           {"filter", to_string(spec.output.filter)},
                           {"file_format", to_string(spec.output.file_format)},
                           {"image", spec.output.image},
                           {"uv_origin", to_string(spec.output.uv_origin)},
                           {"png_compression_level", spec.output.png_compression_level},
                           {"compression", to_string(spec.output.compression)}};
  output["texture"] = spec.output.texture;
  if (spec.output.width > 0) output["width"] = spec.output.width;
  if (spec.output.height > 0) output["height"] = spec.output.height;
  if (spec.output.pixel_format) output["pixel_format"] = to_string(*spec.output.pixel_format);
  j["output"] = std::move(output);
  nlohmann::json options = {{"exact", spec.options.exact},
                            {"tolerance_px", spec.options.tolerance_px},
                            {"jacobian_check", spec.options.jacobian_check}};
  if (spec.options.device) options["device"] = spec.options.device->str();
  if (spec.options.refine) options["refine"] = *spec.options.refine;
  options["optimize"] = to_string(spec.options.optimize);
  j["options"] = std::move(options);
  j["priority"] = spec.priority;
  j["labels"] = encode_job_labels(spec.labels);
  return j;
}

}  // namespace texwarp::proto
