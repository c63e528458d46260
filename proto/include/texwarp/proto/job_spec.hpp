// JobSpec: a job as it travels (POST /v1/jobs body, `texwarp run` file): the texture, then either the warp of an
// image job (features in texture pixels → output pixels) or the mesh part of a mesh job (mesh, region, surface
// features), the output wanted and run options. Mesh-specific JSON is carried as-is for core/mesh's codecs.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/proto/warp_spec.hpp"

namespace texwarp::proto {

enum class JobKind { kImage, kMesh };

// Where the texture comes from: an uploaded blob ("sha256:<64 hex>"), the bytes inline (base64 in JSON,
// decoded here), or a path on the machine that runs the job (the server allows only configured roots).
struct ImageSourceSpec {
  enum class Kind { kBlob, kBase64, kPath };
  Kind kind = Kind::kBlob;
  std::string blob;  // kBlob
  std::string data;  // kBase64: the decoded file bytes
  std::string path;  // kPath
};

// Where the mesh comes from: a blob or a path (OBJ or the JSON mesh form), the JSON mesh form inline, or OBJ
// text inline.
struct MeshSourceSpec {
  enum class Kind { kBlob, kPath, kInline, kObjText };
  enum class Format { kObj, kJson };
  Kind kind = Kind::kInline;
  std::string blob;           // kBlob
  std::string path;           // kPath
  Format format = Format::kObj;  // kBlob, kPath: how to parse the bytes
  nlohmann::json mesh;        // kInline: {"vertices": [[x, y, z], ...], "triangles": [[a, b, c], ...]}
  std::string obj_text;       // kObjText
};

struct MeshJobSpec {
  MeshSourceSpec source;
  std::optional<nlohmann::json> region;  // the region file {"faces"} | {"boundary", "seed_face"}; none: whole mesh
  nlohmann::json features;               // the map-mesh surface feature file (alpha, prealign, features, ...)
  double margin_px = 8.0;                // free band around the embedding in the warped texture
  bool obj_uv_warped = false;            // OBJ UVs into the warped texture (else into the original)
  bool per_triangle = false;             // report: stretch and shear per region triangle
  bool per_vertex = false;               // report: both UVs per region vertex
};

struct OutputSpec {
  int width = 0;   // warped image size; 0: the texture's
  int height = 0;
  std::string interpolation = "bilinear";  // bilinear | bicubic
  std::string border = "transparent";      // transparent | clamp | repeat
  std::string pixel_format;                // uint8 | uint16 | half | float; empty: the texture's
  std::string file_format = "png";         // png | tiff | exr
  bool image = true;                       // write the warped image (a mesh job may want UVs only)
  std::string uv_origin = "bottom_left";   // bottom_left (OBJ, DCC tools) | top_left (glTF)
};

struct JobOptionsSpec {
  bool exact = false;          // a pathline per output pixel instead of the certified lattice
  double tolerance_px = 0.05;  // the certified lattice's bound on the inverse map's error per output pixel
  std::string device;          // "" (the runner's default) | "cpu" | "opencl" | "opencl:<device name substring>"
  bool jacobian_check = false; // image jobs: Jacobian-determinant statistics over the output grid in the report
};

struct JobSpec {
  std::string name;  // a label for people; may be empty
  ImageSourceSpec image;
  std::optional<WarpSpec> warp;     // image job
  std::optional<MeshJobSpec> mesh;  // mesh job (exactly one of warp, mesh)
  OutputSpec output;
  JobOptionsSpec options;

  JobKind kind() const { return mesh ? JobKind::kMesh : JobKind::kImage; }
};

// Limits of the wire format itself (the server adds its own, configurable).
inline constexpr std::size_t kMaxJobNameLength = 200;
inline constexpr int kMaxOutputSide = 32768;
inline constexpr double kMinLatticeTolerancePx = 1e-6;
inline constexpr double kMaxLatticeTolerancePx = 10.0;

}  // namespace texwarp::proto
