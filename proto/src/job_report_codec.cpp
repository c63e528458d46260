// JSON codec of the typed report: see job_report_codec.hpp. Each report type's keys are stated once, in its
// describe() below; an Encoder and a Decoder walk the same description.
#include "texwarp/proto/job_report_codec.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"

namespace texwarp::proto {

const char* to_string(JacobianEstimate map) {
  return map == JacobianEstimate::kVariationalEquation
             ? "inverse (output pixel → source pixel), variational equation at pixel centres"
             : "inverse (output pixel → source pixel), central differences at pixel centres";
}

const char* to_string(WarpMethodReport method) {
  switch (method) {
    case WarpMethodReport::kCertifiedLattice:
      return "certified_lattice";
    case WarpMethodReport::kPerPixel:
      return "per_pixel";
    case WarpMethodReport::kClosedForm:
      return "closed_form";
    case WarpMethodReport::kNone:
      break;
  }
  return "none";
}

namespace {

// Every value of each report-only enum (their names: to_string); the contract's enums have EnumNames tables.
constexpr std::array<JacobianEstimate, 2> values_of(JacobianEstimate) {
  return {JacobianEstimate::kVariationalEquation, JacobianEstimate::kCentralDifferences};
}
constexpr std::array<WarpMethodReport, 4> values_of(WarpMethodReport) {
  return {WarpMethodReport::kCertifiedLattice, WarpMethodReport::kPerPixel, WarpMethodReport::kClosedForm,
          WarpMethodReport::kNone};
}

[[noreturn]] void refuse(const JsonPath& path, const std::string& detail) { throw InputError(path, detail); }

// The sections, each key once: v(key, member) a required key, v.optional (absent when empty), v.nullable (null
// when empty), v.added a key added after the report's first version (this version always writes it; a report from
// an older texwarpd lacks it: std::nullopt, unknown; the schema does not require it). A section flattened into its
// parent object is described in place.

template <class V>
void describe(V& v, TrajectoryReport& t) {
  v("segments", t.segments);
  v("method", t.method);
  v.nullable("min_separation_px", t.min_separation_px);
  v("knots", t.knots);
  v.optional("energy_before", t.energy_before);
  v.optional("energy", t.energy);
  v.optional("waypoints", t.waypoints);
}

template <class V>
void describe(V& v, CertificateReport& c) {
  v("exact", c.exact);
  v("tolerance_px", c.tolerance_px);
  v("max_error_px_estimated", c.max_error_px_estimated);
  v("max_error_px_sampled", c.max_error_px_sampled);
  v.added("max_error_px_bound", c.max_error_px_bound);
  v("sampled_pixels", c.sampled_pixels);
  v("min_jacobian_det", c.min_jacobian_det);
  v("nonpositive_jacobians", c.nonpositive_jacobians);
  v("pathlines", c.pathlines);
  v("jacobian_pathlines", c.jacobian_pathlines);
  v("cells", c.cells);
  v.added("pixel_pathlines", c.pixel_pathlines);
  v("smallest_cell_px", c.smallest_cell_px);
  v.optional("trajectory", c.trajectory);
}

template <class V>
void describe(V& v, WarpSetupReport& w) {
  v("alpha", w.alpha);
  v("prealign", w.prealign);
  v("tolerance_px", w.tolerance_px);
  v("features", w.features);
  v("gradient_features", w.gradient_features);
  v.optional("vertex_seconds", w.vertex_seconds);
}

template <class V>
void describe(V& v, PrealignmentReport& p) {
  v("scale", p.scale);
  v("angle_deg", p.angle_deg);
  v("translation", p.translation);
}

template <class V>
void describe(V& v, ClosestApproachReport& c) {
  v("features", c.features);
  v("t", c.t);
  v("distance_px", c.distance_px);
}

template <class V>
void describe(V& v, DistortionReport& d) {
  v("max_singular_ratio", d.max_singular_ratio);
  v("mean_singular_ratio", d.mean_singular_ratio);
  v("min_det", d.min_det);
}

template <class V>
void describe(V& v, FeatureResidualReport& f) {
  v("feature", f.feature);
  v.optional("id", f.id);
  v("residual_px", f.residual_px);
}

template <class V>
void describe(V& v, ResidualsReport& r) {
  v("max_px", r.max_px);
  v("per_feature", r.per_feature);
}

template <class V>
void describe(V& v, JacobianReport& j) {
  v("map", j.map);
  v.optional("output_size", j.output_size);
  v.optional("grid", j.grid);
  v("step_px", j.step_px);
  v("samples", j.samples);
  v("min_det", j.min_det);
  v("max_det", j.max_det);
  v("nonpositive", j.nonpositive);
}

template <class V>
void describe(V& v, ImageInfoReport& i) {
  v("width", i.width);
  v("height", i.height);
  v("channels", i.channels);
  v("pixel_format", i.pixel_format);
}

template <class V>
void describe(V& v, SamplingReport& s) {
  v("role", s.role);
  v.optional("color_space", s.color_space);
  v.optional("normal_convention", s.normal_convention);
  v("filter", s.filter);
  v("footprint_pixels", s.footprint_pixels);
  v("pyramid_levels", s.pyramid_levels);
  v("repaired_normals", s.repaired_normals);
}

template <class V>
void describe(V& v, OutputImageReport& o) {
  v("file", o.file);
  v("width", o.width);
  v("height", o.height);
  v("channels", o.channels);
  v("pixel_format", o.pixel_format);
  v("interpolation", o.interpolation);
  v("border", o.border);
  v.added("sampling", o.sampling);
}

template <class V>
void describe(V& v, MapReport& m) {
  v("name", m.name);
  v("input", m.input);
  v("output", m.output);
  v("read_s", m.read_s);
  v("sampling_s", m.sampling_s);
  v("write_s", m.write_s);
}

template <class V>
void describe(V& v, MirrorReport& m) {
  v("detected", m.detected);
  v("residual_ratio", m.residual_ratio);
  v("applied", m.applied);
  v.optional("suggestion", m.suggestion);
}

template <class V>
void describe(V& v, ImageJobReport& r) {
  v("input", r.input);
  v("output", r.output);
  v("warp", r.warp);
  v("prealignment", r.prealignment);
  v.nullable("closest_approach", r.closest_approach);
  v.optional("trajectory", r.trajectory);
  v("residuals", r.residuals);
  v.nullable("jacobian", r.jacobian);
  v.added("mirror", r.mirror);
  v.optional("maps", r.maps);
}

template <class V>
void describe(V& v, ImageSizeReport& s) {
  v("width", s.width);
  v("height", s.height);
}

template <class V>
void describe(V& v, MeshCountsReport& m) {
  v("vertices", m.vertices);
  v("faces", m.faces);
  v.added("triangles", m.triangles);
}

template <class V>
void describe(V& v, RegionReport& r) {
  v("faces", r.faces);
  v.added("triangles", r.triangles);
  v("vertices", r.vertices);
  v("boundary_vertices", r.boundary_vertices);
}

template <class V>
void describe(V& v, LscmReport& l) {
  v("pinned_vertices", l.pinned_vertices);
  v("energy", l.energy);
  v("frame_pixels_per_unit", l.frame_pixels_per_unit);
  v("seconds", l.seconds);
}

template <class V>
void describe(V& v, UvQualityReport& q) {
  v("l2_stretch", q.l2_stretch);
  v("linf_stretch", q.linf_stretch);
  v("l2_shear", q.l2_shear);
  v("flipped_triangles", q.flipped_triangles);
  v("degenerate_triangles", q.degenerate_triangles);
  v.added("max_aspect", q.max_aspect);
}

template <class V>
void describe(V& v, UvOptimizationReport& o) {
  v("method", o.method);
  v("applied", o.applied);
  v.optional("skipped", o.skipped);
  v("iterations", o.iterations);
  v("converged", o.converged);
  v("energy_before", o.energy_before);
  v("energy_after", o.energy_after);
  v("before", o.before);
  v("seconds", o.seconds);
}

template <class V>
void describe(V& v, UvUntanglingReport& u) {
  v("applied", u.applied);
  v("flipped_before", u.flipped_before);
  v("flipped_after", u.flipped_after);
  v("rounds", u.rounds);
  v("seconds", u.seconds);
}

template <class V>
void describe(V& v, PlacedFeatureReport& f) {
  v("index", f.index);
  v.optional("id", f.id);
  v("face", f.face);
  v("barycentric", f.barycentric);
  v("position", f.position);
  v("source", f.source);
  v("target_px", f.target_px);
  v("gradient", f.gradient);
  v("residual_px", f.residual_px);
  v.optional("snap_distance", f.snap_distance);
}

template <class V>
void describe(V& v, TriangleReport& t) {
  v("face", t.face);
  v("l2_stretch", t.l2_stretch);
  v("linf_stretch", t.linf_stretch);
  v("shear", t.shear);
  v("flipped", t.flipped);
  v("degenerate", t.degenerate);
  v.optional("source_face", t.source_face);
}

template <class V>
void describe(V& v, SourcePointReport& s) {
  v("face", s.face);
  v("barycentric", s.barycentric);
  v.added("corners", s.corners);
}

template <class V>
void describe(V& v, VertexReport& r) {
  v("vertex", r.vertex);
  v("uv", r.uv);
  v("warped_uv", r.warped_uv);
  v.optional("source", r.source);
}

template <class V>
void describe(V& v, EmbeddingReport& e) {
  v("method", e.method);
  v("lscm_flipped_faces", e.lscm_flipped_faces);
}

template <class V>
void describe(V& v, FlippedFaceReport& f) {
  v("face", f.face);
  v.optional("source_face", f.source_face);
  v("cause", f.cause);
}

template <class V>
void describe(V& v, RefinementReport& r) {
  v("feature_vertices", r.feature_vertices);
  v("split_edges", r.split_edges);
  v("rounds", r.rounds);
  v("added_vertices", r.added_vertices);
  v("added_faces", r.added_faces);
  v("output_vertices", r.output_vertices);
  v("output_faces", r.output_faces);
  v.added("flipped_before", r.flipped_before);
  v.added("flipped_after", r.flipped_after);
  v.added("vertex_limit", r.vertex_limit);
  v.added("stop", r.stop);
  v.added("kept", r.kept);
  v.added("seconds", r.seconds);
}

template <class V>
void describe(V& v, MeshMappingReport& m) {
  v("uv_origin", m.uv_origin);
  v("mesh", m.mesh);
  v("region", m.region);
  v("texture", m.texture);
  v("warped_texture", m.warped_texture);
  v("lscm", m.lscm);
  v("warp", m.warp);
  v.optional("trajectory", m.trajectory);
  describe(v, m.uvs);
  v("max_residual_px", m.max_residual_px);
  v("mean_residual_px", m.mean_residual_px);
  v("vertices_outside_texture", m.vertices_outside_texture);
  v("warped_uvs", m.warped_uvs);
  v.optional("seconds", m.seconds);
  v("features", m.features);
  v.optional("triangles", m.triangles);
  v.optional("vertices", m.vertices);
  v.added("embedding", m.embedding);
  v.added("flips", m.flips);
  v.optional("refinement", m.refinement);
  v.added("untangling", m.untangling);
  v.optional("optimization", m.optimization);
  v.added("texture_sampling", m.texture_sampling);
  v.optional("maps", m.maps);
}

template <class V>
void describe(V& v, StageTimings& s) {
  for (const auto& [stage, name] : EnumNames<LatencyStage>::kTable)
    v.optional(name, s.seconds[StageTimings::index(stage)]);
}

template <class V>
void describe(V& v, TimingsReport& t) {
  v.optional("prepare_s", t.prepare_s);
  v.optional("read_s", t.read_s);
  v.optional("mesh_s", t.mesh_s);
  v.optional("mapping_s", t.mapping_s);
  v.optional("warp_s", t.warp_s);
  v.optional("residuals_s", t.residuals_s);
  v.optional("jacobian_s", t.jacobian_s);
  v.optional("write_s", t.write_s);
  v("total_s", t.total_s);
  if constexpr (V::kDecoding) {
    // Reports written before stages existed have none: they read as no stage measured.
    std::optional<StageTimings> stages;
    v.optional("stages", stages);
    t.stages = stages.value_or(StageTimings{});
  } else {
    v("stages", t.stages);
  }
}

// `section` when encoding (it must be there); emplaced when decoding.
template <class V, class T>
T& variant_section(std::optional<T>& section) {
  if constexpr (V::kDecoding) {
    section.emplace();
  } else if (!section) {
    throw std::invalid_argument("a report without the section of its kind");
  }
  return *section;
}

template <class V>
void describe(V& v, JobReport& r) {
  JobKind kind = r.kind();
  v("kind", kind);
  v("backend", r.backend);
  v.added("double_retries", r.double_retries);
  v("method", r.method);
  v("exact", r.exact);
  v.nullable("certificate", r.certificate);
  if (kind == JobKind::kImage) {
    describe(v, variant_section<V>(r.image));
  } else {
    describe(v, variant_section<V>(r.mesh));
  }
  v("timings", r.timings);
  v("files", r.files);
}

template <class V>
void describe(V& v, FeatureCountsReport& f) {
  v("total", f.total);
  v("positional", f.positional);
  v("gradient", f.gradient);
}

template <class V>
void describe(V& v, CheckOptionsReport& o) {
  v("alpha", o.alpha);
  v("prealign", o.prealign);
  v("tolerance_px", o.tolerance_px);
  v("min_separation_px", o.min_separation_px);
}

template <class V>
void describe(V& v, GradientCheckReport& g) {
  v("feature", g.feature);
  v("expected_scale", g.expected_scale);
  v("measured_scale", g.measured_scale);
  v("expected_angle_deg", g.expected_angle_deg);
  v("angle_error_deg", g.angle_error_deg);
}

template <class V>
void describe(V& v, CheckReport& r) {
  bool valid = r.valid();
  v("valid", valid);
  if (!valid) {
    CheckFailureReport& failure = variant_section<V>(r.failure);
    v("where", failure.where);
    v("error", failure.error);
    return;
  }
  v("features", r.features);
  v("options", r.options);
  v("prealignment", r.prealignment);
  v.optional("closest_approach", r.closest_approach);
  v.optional("trajectory", r.trajectory);
  v("residuals", r.residuals);
  v("gradient_features", r.gradient_features);
  v("jacobian", r.jacobian);
  v.optional("distortion", r.distortion);
  v("method", r.method);
  v("backend", r.backend);
  v("mirror", r.mirror);
}

template <class T>
struct IsStdArray : std::false_type {};
template <class T, std::size_t N>
struct IsStdArray<std::array<T, N>> : std::true_type {};
template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};

template <class T>
nlohmann::json encode_value(const T& value);
template <class T>
void decode_value(const nlohmann::json& j, const JsonPath& path, T& value);

// Writes the described keys into an object. Describing never modifies the report when encoding.
class Encoder {
 public:
  static constexpr bool kDecoding = false;
  explicit Encoder(nlohmann::json& out) : out_(out) {}
  template <class T>
  void operator()(const char* key, const T& value) {
    out_[key] = encode_value(value);
  }
  template <class T>
  void optional(const char* key, const std::optional<T>& value) {
    if (value) out_[key] = encode_value(*value);
  }
  template <class T>
  void nullable(const char* key, const std::optional<T>& value) {
    out_[key] = value ? encode_value(*value) : nlohmann::json(nullptr);
  }
  template <class T>
  void added(const char* key, const std::optional<T>& value) {
    optional(key, value);  // unknown only when relayed from an older report
  }

 private:
  nlohmann::json& out_;
};

// Reads the described keys from an object; keys it does not describe are ignored.
class Decoder {
 public:
  static constexpr bool kDecoding = true;
  Decoder(const nlohmann::json& in, JsonPath path) : in_(in), path_(std::move(path)) {
    if (!in_.is_object()) refuse(path_, "expected an object, got " + json_type_name(in_));
  }
  template <class T>
  void operator()(const char* key, T& value) {
    decode_value(required(key), path_.key(key), value);
  }
  template <class T>
  void optional(const char* key, std::optional<T>& value) {
    const auto it = in_.find(key);
    if (it == in_.end()) {
      value.reset();
    } else {
      decode_value(*it, path_.key(key), value.emplace());
    }
  }
  template <class T>
  void added(const char* key, std::optional<T>& value) {
    optional(key, value);
  }
  template <class T>
  void nullable(const char* key, std::optional<T>& value) {
    const nlohmann::json& j = required(key);
    if (j.is_null()) {
      value.reset();
    } else {
      decode_value(j, path_.key(key), value.emplace());
    }
  }

 private:
  const nlohmann::json& required(const char* key) const {
    const auto it = in_.find(key);
    if (it == in_.end()) refuse(path_.key(key), "required key is missing");
    return *it;
  }

  const nlohmann::json& in_;
  JsonPath path_;
};

template <class T>
nlohmann::json encode_value(const T& value) {
  if constexpr (std::is_same_v<T, double>) {
    return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
  } else if constexpr (std::is_enum_v<T>) {
    return to_string(value);
  } else if constexpr (IsStdArray<T>::value || IsVector<T>::value) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& element : value) out.push_back(encode_value(element));
    return out;
  } else if constexpr (requires(Encoder & e, T & t) { describe(e, t); }) {
    nlohmann::json out = nlohmann::json::object();
    Encoder encoder(out);
    describe(encoder, const_cast<T&>(value));
    return out;
  } else {
    return value;  // bool, integers, strings
  }
}

template <class T>
void decode_value(const nlohmann::json& j, const JsonPath& path, T& value) {
  const auto expected = [&](const char* what) {
    refuse(path, std::string("expected ") + what + ", got " + json_type_name(j));
  };
  if constexpr (std::is_same_v<T, double>) {
    if (j.is_null()) {
      value = std::numeric_limits<double>::quiet_NaN();  // the encoder's form of a number that is not finite
    } else {
      if (!j.is_number()) expected("a number");
      value = j.get<double>();
    }
  } else if constexpr (std::is_same_v<T, bool>) {
    if (!j.is_boolean()) expected("true or false");
    value = j.get<bool>();
  } else if constexpr (std::is_integral_v<T>) {
    if (!j.is_number_integer() || (std::is_unsigned_v<T> && !j.is_number_unsigned())) {
      expected(std::is_unsigned_v<T> ? "a non-negative integer" : "an integer");
    }
    value = j.get<T>();
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!j.is_string()) expected("a string");
    value = j.get<std::string>();
  } else if constexpr (std::is_enum_v<T>) {
    if (!j.is_string()) expected("a string");
    const std::string name = j.get<std::string>();
    if constexpr (WireEnum<T>) {
      if (const auto v = enum_from_name<T>(name)) {
        value = *v;
        return;
      }
    } else {
      for (const T candidate : values_of(T{})) {
        if (name == to_string(candidate)) {
          value = candidate;
          return;
        }
      }
    }
    refuse(path, "unknown value \"" + name + "\"");
  } else if constexpr (IsStdArray<T>::value) {
    if (!j.is_array() || j.size() != value.size()) {
      refuse(path, "expected an array of " + std::to_string(value.size()) + ", got " + json_type_name(j));
    }
    for (std::size_t i = 0; i < value.size(); ++i) decode_value(j[i], path.index(i), value[i]);
  } else if constexpr (IsVector<T>::value) {
    if (!j.is_array()) expected("an array");
    value.resize(j.size());
    for (std::size_t i = 0; i < value.size(); ++i) decode_value(j[i], path.index(i), value[i]);
  } else {
    Decoder decoder(j, path);
    describe(decoder, value);
  }
}

template <class T>
T decode_report(const nlohmann::json& value, const JsonPath& path) {
  T report;
  decode_value(value, path, report);
  return report;
}

}  // namespace

nlohmann::json encode_job_report(const JobReport& report) { return encode_value(report); }
JobReport decode_job_report(const nlohmann::json& value, const JsonPath& path) {
  return decode_report<JobReport>(value, path);
}

nlohmann::json encode_check_report(const CheckReport& report) { return encode_value(report); }
CheckReport decode_check_report(const nlohmann::json& value, const JsonPath& path) {
  return decode_report<CheckReport>(value, path);
}

nlohmann::json encode_mesh_mapping_report(const MeshMappingReport& report) { return encode_value(report); }
MeshMappingReport decode_mesh_mapping_report(const nlohmann::json& value, const JsonPath& path) {
  return decode_report<MeshMappingReport>(value, path);
}

nlohmann::json encode_certificate_report(const CertificateReport& report) { return encode_value(report); }
CertificateReport decode_certificate_report(const nlohmann::json& value, const JsonPath& path) {
  return decode_report<CertificateReport>(value, path);
}

}  // namespace texwarp::proto
