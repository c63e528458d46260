// JobSpec: a job as it travels (POST /v1/jobs body, `texwarp run` file), as typed values: the texture, then either
// the warp of an image job (features in texture pixels → output pixels) or the mesh part of a mesh job (mesh,
// region, surface features), the output wanted, run options, and its place in the queue (priority, labels). Decoded
// and validated by job_spec_codec.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "texwarp/proto/device_spec.hpp"
#include "texwarp/proto/enum_names.hpp"
#include "texwarp/proto/export.hpp"
#include "texwarp/proto/gltf_selection_spec.hpp"
#include "texwarp/proto/image_role.hpp"
#include "texwarp/proto/job_labels.hpp"
#include "texwarp/proto/mesh_data_spec.hpp"
#include "texwarp/proto/output_enums.hpp"
#include "texwarp/proto/region_spec.hpp"
#include "texwarp/proto/surface_feature_spec.hpp"
#include "texwarp/proto/udim_tiles.hpp"
#include "texwarp/proto/uv_optimize.hpp"
#include "texwarp/proto/warp_spec.hpp"

namespace texwarp::proto {

enum class JobKind { kImage, kMesh };

template <>
struct EnumNames<JobKind> {
  static constexpr std::array<std::pair<JobKind, const char*>, 2> kTable = {
      {{JobKind::kImage, "image"}, {JobKind::kMesh, "mesh"}}};
};

// Where the texture comes from: an uploaded blob ("sha256:<64 hex>"), the bytes inline (base64 in JSON,
// decoded here), a path on the machine that runs the job (the server allows only configured roots), or a UDIM
// texture's tiles one by one (blobs or inline), as a path with <UDIM> names them on that machine.
// What the image holds (image_role.hpp) travels with it: its role (none: from the file, colour for 8/16-bit files,
// data for float ones), a colour space overriding the file's, and a normal map's convention.
// One UDIM tile given by itself (an image source's "tiles"): its number and its file, uploaded or inline.
struct UdimTileSource {
  int number = kFirstUdimTile;
  std::string blob;  // a blob id, or
  std::string data;  // the decoded file bytes (base64)
  friend TEXWARP_API bool operator==(const UdimTileSource&, const UdimTileSource&);
};

struct ImageSourceSpec {
  enum class Kind { kBlob, kBase64, kPath, kTiles };
  Kind kind = Kind::kBlob;
  std::string blob;                   // kBlob
  std::string data;                   // kBase64: the decoded file bytes
  std::string path;                   // kPath
  std::vector<UdimTileSource> tiles;  // kTiles: a UDIM texture's tiles by number, as a <UDIM> path's would be
  std::optional<ImageRole> role;
  std::string color_space;                                         // empty: the file's
  NormalConvention normal_convention = NormalConvention::kOpenGl;  // role normal
  friend TEXWARP_API bool operator==(const ImageSourceSpec&, const ImageSourceSpec&);
};

// One map of a texture set (a job's "images"): its source and what it holds, as `image`, and the name its warped
// output is written under ("<name>.<file_format>"; default: a path's file name without its extension).
struct NamedImageSpec {
  ImageSourceSpec source;
  std::string name;
  friend TEXWARP_API bool operator==(const NamedImageSpec&, const NamedImageSpec&);
};

// How a mesh file or blob is parsed: OBJ, the JSON mesh form, glTF 2.0 (.gltf JSON with embedded buffers, or .glb).
enum class MeshFormat { kObj, kJson, kGltf, kGlb };

template <>
struct EnumNames<MeshFormat> {
  static constexpr std::array<std::pair<MeshFormat, const char*>, 4> kTable = {
      {{MeshFormat::kObj, "obj"}, {MeshFormat::kJson, "json"}, {MeshFormat::kGltf, "gltf"}, {MeshFormat::kGlb, "glb"}}};
};

// Where the mesh comes from: a blob or a path (OBJ, the JSON mesh form or glTF), the JSON mesh form inline, or OBJ
// text inline.
struct MeshSourceSpec {
  enum class Kind { kBlob, kPath, kInline, kObjText };
  using Format = MeshFormat;
  Kind kind = Kind::kInline;
  std::string blob;                       // kBlob
  std::string path;                       // kPath
  Format format = Format::kObj;           // kBlob, kPath: how to parse the bytes
  MeshDataSpec mesh;                      // kInline
  std::string obj_text;                   // kObjText
  std::optional<GltfSelectionSpec> gltf;  // kBlob, kPath of a glTF format: the primitive (none: the first)
  friend TEXWARP_API bool operator==(const MeshSourceSpec&, const MeshSourceSpec&);
};

// Which texture a mesh job's OBJ UVs point into.
enum class ObjUv { kOriginal, kWarped };

template <>
struct EnumNames<ObjUv> {
  static constexpr std::array<std::pair<ObjUv, const char*>, 2> kTable = {
      {{ObjUv::kOriginal, "original"}, {ObjUv::kWarped, "warped"}}};
};

struct MeshJobSpec {
  MeshSourceSpec source;
  std::optional<RegionSpec> region;  // none: the whole mesh
  SurfaceFeatureSetSpec features;    // the map-mesh surface feature file's content
  double margin_px = 8.0;            // free band around the embedding in the warped texture
  ObjUv obj_uv = ObjUv::kOriginal;   // OBJ UVs into the original texture or the warped one
  bool per_triangle = false;         // report: stretch and shear per region triangle
  bool per_vertex = false;           // report: both UVs per region vertex
  friend TEXWARP_API bool operator==(const MeshJobSpec&, const MeshJobSpec&);
};

struct OutputSpec {
  int width = 0;  // warped image size; 0: the texture's
  int height = 0;
  Interpolation interpolation = Interpolation::kBilinear;
  Border border = Border::kTransparent;
  SamplingFilter filter = SamplingFilter::kFootprint;
  std::optional<PixelFormat> pixel_format;  // none: the texture's
  FileFormat file_format = FileFormat::kPng;
  bool image = true;  // write the warped image (a mesh job may want UVs only)
  UvOrigin uv_origin = UvOrigin::kBottomLeft;
  int png_compression_level = kDefaultPngCompressionLevel;  // 0–9 (output_enums.hpp)
  Compression compression = Compression::kFast;             // TIFF and EXR
  // TIFF and EXR: a render-ready texture (tiled, MIP-mapped, the role's colour space recorded; OpenImageIO's
  // make_texture); a TIFF one is written as .tx.
  bool texture = false;
  friend TEXWARP_API bool operator==(const OutputSpec&, const OutputSpec&);
};

struct JobOptionsSpec {
  bool exact = false;                // a pathline per output pixel instead of the certified lattice
  double tolerance_px = 0.05;        // the certified lattice's bound on the inverse map's error per output pixel
  std::optional<DeviceSpec> device;  // none: the runner's default
  bool jacobian_check = false;       // image jobs: Jacobian-determinant statistics over the output grid
  // Mesh jobs: split the triangles whose UVs flip until none does, and faces at features; absent: for meshes whose
  // output can take new faces (OBJ, JSON), not glTF.
  std::optional<bool> refine;
  UvOptimize optimize = UvOptimize::kStretch;  // mesh jobs: what is done with the flip-free UVs
  friend TEXWARP_API bool operator==(const JobOptionsSpec&, const JobOptionsSpec&);
};

struct JobSpec {
  std::string name;                    // a label for people; may be empty
  ImageSourceSpec image;               // the texture, unless `images` is given
  std::vector<NamedImageSpec> images;  // image jobs: a texture set, 1…kMaxJobImages maps warped by one map
  std::optional<WarpSpec> warp;        // image job
  std::optional<MeshJobSpec> mesh;     // mesh job (exactly one of warp, mesh)
  OutputSpec output;
  JobOptionsSpec options;
  int priority = 0;  // kMinJobPriority…kMaxJobPriority: higher runs first, first come first served within
  JobLabels labels;  // filters of GET /v1/jobs?label=k=v

  JobKind kind() const { return mesh ? JobKind::kMesh : JobKind::kImage; }
  bool is_set() const { return !images.empty(); }
  friend TEXWARP_API bool operator==(const JobSpec&, const JobSpec&);
};

// Limits of the wire format itself (the server adds its own, configurable).
inline constexpr std::size_t kMaxJobNameLength = 200;
inline constexpr int kMaxOutputSide = 32768;
inline constexpr double kMinLatticeTolerancePx = 1e-6;
inline constexpr double kMaxLatticeTolerancePx = 10.0;
inline constexpr int kMinJobPriority = -1000;
inline constexpr int kMaxJobPriority = 1000;
// The most maps of a texture set (a job's "images", `texwarp warp --in` repeated), and the longest output name.
inline constexpr std::size_t kMaxJobImages = 16;
inline constexpr std::size_t kMaxImageNameLength = 100;

}  // namespace texwarp::proto
