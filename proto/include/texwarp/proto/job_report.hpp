// The report, typed: a job's report.json (image or mesh job), what `texwarp check` prints and `texwarp map-mesh
// --report` writes, built from shared sections (certificate, warp set-up, residuals, Jacobian statistics, mesh
// mapping quality, timings). JSON codec: job_report_codec.hpp; schema: proto/schema/report.schema.json. A key added
// after the report's first version is a std::optional here: absent (unknown) in a report from an older texwarpd.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "texwarp/proto/export.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/latency_stage.hpp"
#include "texwarp/proto/mesh_flips_report.hpp"
#include "texwarp/proto/mirror_report.hpp"
#include "texwarp/proto/trajectory_method.hpp"
#include "texwarp/proto/uv_optimize.hpp"
#include "texwarp/proto/warp_spec.hpp"

namespace texwarp::proto {

// The features' planned trajectories ("trajectory"): K straight segments between knots 0 = t_0 < … < t_K = 1.
struct TrajectoryReport {
  std::size_t segments = 1;
  TrajectoryMethod method = TrajectoryMethod::kStraight;
  std::optional<double> min_separation_px;  // the closest any two features come; null without two features
  std::vector<double> knots;
  // The pair energy Σ∫|c_ij|² dt of the trajectories as planned and as kept, where the planner tried to lower it.
  std::optional<double> energy_before;
  std::optional<double> energy;
  // On request (`texwarp check --trajectories`): waypoints[k][i], feature i at knot k, pre-aligned frame (pixels).
  std::optional<std::vector<std::vector<std::array<double, 2>>>> waypoints;
  TEXWARP_API bool operator==(const TrajectoryReport&) const;
};

// What the image warp showed about its accuracy and folds (the CLI's --certificate file; "certificate").
struct CertificateReport {
  bool exact = false;                        // every output pixel by its own pathline
  double tolerance_px = 0.0;                 // the error bound asked for, pixels
  double max_error_px_estimated = 0.0;       // at the lattice's check points and edges, pixels
  double max_error_px_sampled = 0.0;         // on random output pixels against their own pathline, pixels
  std::optional<double> max_error_px_bound;  // bound on the error at every output pixel, pixels (added)
  std::uint64_t sampled_pixels = 0;
  double min_jacobian_det = 0.0;  // of the inverse map (not finite: null in JSON, NaN here)
  std::uint64_t nonpositive_jacobians = 0;
  std::uint64_t pathlines = 0;
  std::uint64_t jacobian_pathlines = 0;
  std::uint64_t cells = 0;
  std::optional<std::uint64_t> pixel_pathlines;  // lattice pixels kept at their own pathline (added)
  int smallest_cell_px = 0;
  std::optional<TrajectoryReport> trajectory;  // the CLI's certificate file: the trajectories the warp followed
  TEXWARP_API bool operator==(const CertificateReport&) const;
};

// The warp's parameters and feature counts ("warp").
struct WarpSetupReport {
  double alpha = 2.0;
  Prealign prealign = Prealign::kSimilarity;
  double tolerance_px = 0.0;  // pathline tolerance, pixels
  std::size_t features = 0;
  std::size_t gradient_features = 0;
  std::optional<double> vertex_seconds;  // mesh: the inverse map of the region's vertices
  TEXWARP_API bool operator==(const WarpSetupReport&) const;
};

// The pre-alignment similarity S (Section 3.3): p ↦ scale·e^{i·angle}·p + translation.
struct PrealignmentReport {
  double scale = 1.0;
  double angle_deg = 0.0;
  std::array<double, 2> translation{};  // pixels
  TEXWARP_API bool operator==(const PrealignmentReport&) const;
};

// The warp's distortion over the output grid: the inverse map's Jacobian singular-value ratio σ1/σ2 (1 for a
// conformal map) and its determinant.
struct DistortionReport {
  double max_singular_ratio = 1.0;
  double mean_singular_ratio = 1.0;
  double min_det = 0.0;
  TEXWARP_API bool operator==(const DistortionReport&) const;
};

// The two features whose trajectories come closest, when, and how close.
struct ClosestApproachReport {
  std::array<std::string, 2> features;  // "features[3] (\"eye\")"
  double t = 0.0;
  double distance_px = 0.0;
  TEXWARP_API bool operator==(const ClosestApproachReport&) const;
};

struct FeatureResidualReport {
  std::string feature;            // "features[3] (\"eye\")"
  std::optional<std::string> id;  // image jobs: the feature's id ("" when it has none); check: absent
  double residual_px = 0.0;       // |f(source) − target|, pixels
  TEXWARP_API bool operator==(const FeatureResidualReport&) const;
};

struct ResidualsReport {
  double max_px = 0.0;
  std::vector<FeatureResidualReport> per_feature;
  TEXWARP_API bool operator==(const ResidualsReport&) const;
};

// How the Jacobian determinants of the inverse map were obtained.
enum class JacobianEstimate { kVariationalEquation, kCentralDifferences };

// Jacobian-determinant statistics of the inverse map over a grid of output pixel centres.
struct JacobianReport {
  JacobianEstimate map = JacobianEstimate::kVariationalEquation;
  std::optional<std::array<int, 2>> output_size;  // check: the output the grid covers
  std::optional<std::array<int, 2>> grid;         // check: grid nodes per side
  int step_px = 1;
  std::size_t samples = 0;
  double min_det = 0.0;  // not finite: null in JSON, NaN here
  double max_det = 0.0;
  std::size_t nonpositive = 0;
  TEXWARP_API bool operator==(const JacobianReport&) const;
};

struct ImageInfoReport {
  int width = 0;
  int height = 0;
  int channels = 0;
  PixelFormat pixel_format = PixelFormat::kUint8;
  TEXWARP_API bool operator==(const ImageInfoReport&) const;
};

// How the warped image was sampled: the source's role (and its colour space or normal convention), the filter,
// how many output pixels averaged their footprint (where the map minifies), the MIP levels built for it, and the
// normal map's texels repaired (zero length or below the surface).
struct SamplingReport {
  ImageRole role = ImageRole::kData;
  std::optional<std::string> color_space;             // colour images: "sRGB" or "linear"
  std::optional<NormalConvention> normal_convention;  // normal maps
  SamplingFilter filter = SamplingFilter::kFootprint;
  std::size_t footprint_pixels = 0;
  int pyramid_levels = 0;
  std::size_t repaired_normals = 0;
  TEXWARP_API bool operator==(const SamplingReport&) const;
};

struct OutputImageReport {
  std::string file;  // "warped.png"
  int width = 0;
  int height = 0;
  int channels = 0;
  PixelFormat pixel_format = PixelFormat::kUint8;
  Interpolation interpolation = Interpolation::kBilinear;
  Border border = Border::kTransparent;
  std::optional<SamplingReport> sampling;  // added
  TEXWARP_API bool operator==(const OutputImageReport&) const;
};

// One map of a texture set (an image job's "images"): its name, the input read, the output written and how it was
// sampled, and its own stages (the map of the output grid is shared).
struct MapReport {
  std::string name;  // the job's images[i].name
  ImageInfoReport input;
  OutputImageReport output;  // with its sampling (role, filter, …)
  double read_s = 0.0;       // decoding the map
  double sampling_s = 0.0;   // resampling it through the shared map
  double write_s = 0.0;      // encoding and writing its file
  TEXWARP_API bool operator==(const MapReport&) const;
};

// The sections of an image job's report.
struct ImageJobReport {
  ImageInfoReport input;
  OutputImageReport output;
  WarpSetupReport warp;
  PrealignmentReport prealignment;
  std::optional<ClosestApproachReport> closest_approach;  // null without two features
  std::optional<TrajectoryReport> trajectory;
  ResidualsReport residuals;
  std::optional<JacobianReport> jacobian;  // null unless options.jacobian_check
  std::optional<MirrorReport> mirror;      // added
  // A texture set: every map in the job's order (`input` and `output` above are its first's); absent for one image.
  std::optional<std::vector<MapReport>> maps;
  TEXWARP_API bool operator==(const ImageJobReport&) const;
};

struct ImageSizeReport {
  int width = 0;
  int height = 0;
  TEXWARP_API bool operator==(const ImageSizeReport&) const;
};

// Faces are the input file's (an OBJ's quad or n-gon counts once); triangles are what they are cut into, and
// what the per-triangle entries, LSCM and the warp work on. A triangle mesh has as many of each.
struct MeshCountsReport {
  int vertices = 0;
  int faces = 0;
  std::optional<int> triangles;  // added
  TEXWARP_API bool operator==(const MeshCountsReport&) const;
};

// `faces`: the input faces with a triangle in the region; with `refine`, the output's (triangles) faces.
struct RegionReport {
  int faces = 0;
  int vertices = 0;
  std::size_t boundary_vertices = 0;
  std::optional<int> triangles;  // added
  TEXWARP_API bool operator==(const RegionReport&) const;
};

struct LscmReport {
  std::array<int, 2> pinned_vertices{};  // mesh vertex ids
  double energy = 0.0;                   // conformal energy of the embedding
  double frame_pixels_per_unit = 0.0;    // warped-texture pixels per world unit
  double seconds = 0.0;
  TEXWARP_API bool operator==(const LscmReport&) const;
};

// Distortion of UVs over the region (Sander et al. 2001; Sheffer et al. 2005).
struct UvQualityReport {
  double l2_stretch = 0.0;  // 1 for an isometry
  double linf_stretch = 0.0;
  double l2_shear = 0.0;  // 0 for a conformal map
  int flipped_triangles = 0;
  int degenerate_triangles = 0;
  std::optional<double> max_aspect;  // largest σ1/σ2 of a triangle's map: 1 for a conformal map (added)
  TEXWARP_API bool operator==(const UvQualityReport&) const;
};

// What `optimize: stretch` did to the UVs into the original texture (SLIM on the symmetric Dirichlet energy, the pins
// fixed, never through a flip): the UVs' quality before it (after refinement) and the energy it lowered.
struct UvOptimizationReport {
  UvOptimize method = UvOptimize::kStretch;
  bool applied = false;                // false: skipped (`skipped` says why)
  std::optional<std::string> skipped;  // earlier versions: UV triangles still flipped (now optimised around them)
  int iterations = 0;
  bool converged = false;
  double energy_before = 0.0;  // mean symmetric Dirichlet energy, 4 for an isometry
  double energy_after = 0.0;
  UvQualityReport before;
  double seconds = 0.0;
  TEXWARP_API bool operator==(const UvOptimizationReport&) const;
};

// What optimize: stretch did first when the UVs flipped: untangling (core/mesh/uv_untangling.hpp), features held.
struct UvUntanglingReport {
  bool applied = false;    // the UVs were replaced (by a result with fewer flipped triangles)
  int flipped_before = 0;  // UV triangles not counter-clockwise as written, before it
  int flipped_after = 0;   // after it
  int rounds = 0;
  double seconds = 0.0;
  TEXWARP_API bool operator==(const UvUntanglingReport&) const;
};

struct PlacedFeatureReport {
  std::size_t index = 0;          // in the surface feature file
  std::optional<std::string> id;  // absent when the feature has none
  int face = 0;                   // mesh face id
  std::array<double, 3> barycentric{};
  std::array<double, 3> position{};   // world units
  std::array<double, 2> source{};     // texture pixels
  std::array<double, 2> target_px{};  // warped-texture pixels
  bool gradient = false;
  double residual_px = 0.0;             // |UVs at its surface point − source|, texture pixels
  std::optional<double> snap_distance;  // point targets moved onto the surface, world units; absent when 0
  TEXWARP_API bool operator==(const PlacedFeatureReport&) const;
};

struct TriangleReport {
  int face = 0;
  double l2_stretch = 0.0;
  double linf_stretch = 0.0;
  double shear = 0.0;
  bool flipped = false;
  bool degenerate = false;
  std::optional<int> source_face;  // with `refine`: the input face it lies in (`face` is then an output id)
  TEXWARP_API bool operator==(const TriangleReport&) const;
};

struct VertexReport {
  int vertex = 0;                           // mesh vertex id
  std::array<double, 2> uv{};               // into the original texture
  std::array<double, 2> warped_uv{};        // into the warped texture
  std::optional<SourcePointReport> source;  // a vertex `refine` added: where it lies on the input mesh
  TEXWARP_API bool operator==(const VertexReport&) const;
};

// A mesh mapping: `texwarp map-mesh --report` and the body of a mesh job's report.
struct MeshMappingReport {
  UvOrigin uv_origin = UvOrigin::kBottomLeft;
  MeshCountsReport mesh;
  RegionReport region;
  ImageSizeReport texture;
  ImageSizeReport warped_texture;
  LscmReport lscm;
  WarpSetupReport warp;
  std::optional<TrajectoryReport> trajectory;
  UvQualityReport uvs;  // UVs into the original texture: at the top level of the JSON object
  double max_residual_px = 0.0;
  double mean_residual_px = 0.0;
  int vertices_outside_texture = 0;
  UvQualityReport warped_uvs;
  std::optional<double> seconds;  // map-mesh: the whole command
  std::vector<PlacedFeatureReport> features;
  std::optional<std::vector<TriangleReport>> triangles;  // on request (per_triangle)
  std::optional<std::vector<VertexReport>> vertices;     // on request (per_vertex)
  std::optional<EmbeddingReport> embedding;              // LSCM, or its repair (added)
  std::optional<std::vector<FlippedFaceReport>> flips;   // every flipped UV triangle (added)
  std::optional<RefinementReport> refinement;            // with `refine`
  std::optional<UvUntanglingReport> untangling;          // with `optimize: stretch` when UVs flipped (added)
  std::optional<UvOptimizationReport> optimization;      // with `optimize` (added)
  std::optional<SamplingReport> texture_sampling;        // the warped texture's sampling (added; null: no image)
  // A mesh job's texture set: every map in the job's order (texture_sampling is its first's); absent for one image.
  std::optional<std::vector<MapReport>> maps;
  TEXWARP_API bool operator==(const MeshMappingReport&) const;
};

// How the image warp made its map: pathlines on a certified lattice, one per pixel, none because the field is zero
// and the map is S⁻¹ in closed form, or no image at all (a mesh job without image).
enum class WarpMethodReport { kCertifiedLattice, kPerPixel, kClosedForm, kNone };

// Seconds per phase of a job; a phase the job did not have is absent.
struct TimingsReport {
  std::optional<double> prepare_s;
  std::optional<double> read_s;
  std::optional<double> mesh_s;
  std::optional<double> mapping_s;
  std::optional<double> warp_s;
  std::optional<double> residuals_s;
  std::optional<double> jacobian_s;
  std::optional<double> write_s;
  double total_s = 0.0;
  StageTimings stages;  // the same time by latency stage (latency_stage.hpp)
  TEXWARP_API bool operator==(const TimingsReport&) const;
};

// report.json of a job: exactly one of `image` (an image job) and `mesh` (a mesh job).
struct JobReport {
  std::string backend;  // "cpu", "opencl:<device>"
  // Backend calls whose float32 pathline steps collapsed and that ran again in double (OpenCL, added)
  std::optional<std::uint64_t> double_retries;
  WarpMethodReport method = WarpMethodReport::kCertifiedLattice;
  bool exact = false;
  std::optional<CertificateReport> certificate;  // null for a mesh job without a warped image
  std::optional<ImageJobReport> image;
  std::optional<MeshMappingReport> mesh;
  TimingsReport timings;
  std::vector<std::string> files;  // the job's result files, report.json last
  JobKind kind() const { return mesh ? JobKind::kMesh : JobKind::kImage; }
  TEXWARP_API bool operator==(const JobReport&) const;
};

struct FeatureCountsReport {
  std::size_t total = 0;
  std::size_t positional = 0;
  std::size_t gradient = 0;
  TEXWARP_API bool operator==(const FeatureCountsReport&) const;
};

struct CheckOptionsReport {
  double alpha = 2.0;
  Prealign prealign = Prealign::kSimilarity;
  double tolerance_px = 0.0;
  double min_separation_px = 0.0;
  TEXWARP_API bool operator==(const CheckOptionsReport&) const;
};

// A gradient feature's Jacobian measured against the one it asks for (S·e^{iφ}, Eq. 4).
struct GradientCheckReport {
  std::string feature;
  double expected_scale = 1.0;
  double measured_scale = 1.0;
  double expected_angle_deg = 0.0;
  double angle_error_deg = 0.0;
  TEXWARP_API bool operator==(const GradientCheckReport&) const;
};

struct CheckFailureReport {
  std::string where;  // the JSON path of the offender
  std::string error;
  TEXWARP_API bool operator==(const CheckFailureReport&) const;
};

// What `texwarp check` prints: {"valid": false, where, error} for a feature file the method refuses, else the rest.
struct CheckReport {
  std::optional<CheckFailureReport> failure;
  FeatureCountsReport features;
  CheckOptionsReport options;
  PrealignmentReport prealignment;
  std::optional<ClosestApproachReport> closest_approach;  // absent without two features
  std::optional<TrajectoryReport> trajectory;
  ResidualsReport residuals;
  std::vector<GradientCheckReport> gradient_features;
  JacobianReport jacobian;
  std::optional<DistortionReport> distortion;  // the field's map (variational equation)
  std::string method;                          // field | tps | mls
  std::string backend;
  MirrorReport mirror;
  bool valid() const { return !failure; }
  TEXWARP_API bool operator==(const CheckReport&) const;
};

}  // namespace texwarp::proto
