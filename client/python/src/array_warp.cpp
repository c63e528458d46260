// texwarp.warp / texwarp.map_points over NumPy arrays: see array_warp.hpp.
#include "array_warp.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "python_failure.hpp"
#include "python_json.hpp"
#include "texwarp/core/closed_form_warp.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/feature_conversion.hpp"
#include "texwarp/core/image_io.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/sample_conversion.hpp"
#include "texwarp/core/sampling_report.hpp"
#include "texwarp/core/warp_certificate_json.hpp"
#include "texwarp/core/warp_problem_report.hpp"
#include "texwarp/proto/device_spec.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_report_codec.hpp"
#include "texwarp/proto/problem_details.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"
#include "texwarp/runner/backend_cache.hpp"

namespace texwarp::python {
namespace {

namespace py = pybind11;

// The element types an image array may hold, as stored: float16 and float64 arrays are converted to float32.
enum class Sample { kUint8, kUint16, kFloat32 };

// Runs `body` as guarded() does, but an InputError becomes texwarp.InputError titled "Invalid argument", with the
// whole place as its path ("features: $.features[2].source", "image", "backend").
template <typename F>
auto argument_guarded(F&& body) {
  return guarded([&] {
    try {
      return body();
    } catch (const InputError& e) {
      Failure f;
      f.kind = Failure::Kind::kInput;
      f.type = std::string(proto::kProblemTypePrefix) + "invalid-job";
      f.title = "Invalid argument";
      f.path = e.where().str();
      f.detail = e.detail();
      throw FailureError(f);
    }
  });
}

[[noreturn]] void refuse(const std::string& argument, const std::string& detail) {
  throw InputError(InputLocation::flag(argument), detail);
}

std::string shape_text(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t i = 0; i < array.ndim(); ++i) {
    if (i > 0) text += ", ";
    text += std::to_string(array.shape(i));
  }
  return text + (array.ndim() == 1 ? ",)" : ")");
}

// The feature-file form ({"features": [...], "alpha": …} or a bare list of features) as a WarpSpec; errors at
// "features: $.json.path". `alpha` and `prealign`, when given, replace the file's.
proto::WarpSpec decode_features(const py::handle& features, std::optional<double> alpha,
                                const std::optional<std::string>& prealign) {
  nlohmann::json j;
  try {
    j = to_json(features);
  } catch (const FailureError& e) {
    Failure f = e.failure();
    f.path = "features: $";
    throw FailureError(f);
  }
  if (j.is_array()) j = nlohmann::json{{"features", std::move(j)}};
  proto::WarpSpec spec;
  try {
    spec = proto::decode_warp_spec(j);
  } catch (const InputError& e) {
    throw InputError(e.where().in_file("features"), e.detail());
  }
  if (alpha) {
    if (!std::isfinite(*alpha) || *alpha <= 0.0)
      refuse("alpha", "must be a finite number > 0, got " + std::to_string(*alpha));
    spec.alpha = *alpha;
  }
  if (prealign) spec.prealign = proto::parse_enum<proto::Prealign>(*prealign, InputLocation::flag("prealign"));
  return spec;
}

WarpProblem problem_of(const proto::WarpSpec& spec, int mirror_width) {
  try {
    std::vector<Feature> features = features_from_spec(spec);
    if (mirror_width > 0) features = mirror_features(std::move(features), mirror_width);
    return WarpProblem(std::move(features), options_from_spec(spec));
  } catch (const InputError& e) {
    throw InputError(e.where().in_file("features"), e.detail());
  }
}

// The compute backend a call names: a CPU backend of its own, or the process's OpenCL backend for that device, made
// on first use and kept (a context and built programs), lent to one call at a time.
class BackendLease {
 public:
  explicit BackendLease(const proto::DeviceSpec& device) {
    if (device.kind == proto::DeviceSpec::Kind::kCpu) {
      cpu_ = std::make_unique<CpuBackend>();
      backend_ = cpu_.get();
      return;
    }
    lock_ = std::unique_lock(shared().mutex);
    backend_ = &shared().cache.get(device, InputLocation::flag("backend"));
  }
  WarpBackend& operator*() const { return *backend_; }

 private:
  struct Shared {
    std::mutex mutex;
    runner::BackendCache cache;
  };
  // Never destroyed: an OpenCL context torn down after the driver at the interpreter's exit would crash it.
  static Shared& shared() {
    static auto* kept = new Shared();
    return *kept;
  }

  std::unique_ptr<CpuBackend> cpu_;
  std::unique_lock<std::mutex> lock_;
  WarpBackend* backend_ = nullptr;
};

// An image argument as numbers: an H×W or H×W×C array (C ≤ 4), its element type checked; float16 and float64
// converted to float32; C order, native byte order.
struct ImageArray {
  py::array array;
  Sample sample = Sample::kUint8;
  PixelFormat format = PixelFormat::kUint8;  // the file format it stands for (the default role follows it)
  int width = 0;
  int height = 0;
  int channels = 0;
  bool two_dimensional = false;
};

ImageArray image_array(const py::handle& image) {
  py::array array;
  try {
    array = py::module_::import("numpy").attr("asarray")(image);
  } catch (const py::error_already_set& e) {
    refuse("image", std::string("is not an array: ") + e.what());
  }
  ImageArray in;
  if ((array.ndim() != 2 && array.ndim() != 3) || (array.ndim() == 3 && (array.shape(2) < 1 || array.shape(2) > 4))) {
    refuse("image", "expected an H×W or H×W×C array with C ≤ 4, got shape " + shape_text(array));
  }
  in.two_dimensional = array.ndim() == 2;
  const py::dtype dtype = array.dtype();
  const char kind = dtype.kind();
  const auto size = dtype.itemsize();
  if (kind == 'u' && size == 1) {
    in.sample = Sample::kUint8;
    in.format = PixelFormat::kUint8;
    in.array = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(array);
  } else if (kind == 'u' && size == 2) {
    in.sample = Sample::kUint16;
    in.format = PixelFormat::kUint16;
    in.array = py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>::ensure(array);
  } else if (kind == 'f' && (size == 2 || size == 4 || size == 8)) {
    in.sample = Sample::kFloat32;
    in.format = size == 2 ? PixelFormat::kHalf : PixelFormat::kFloat;
    in.array = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(array);
  } else {
    refuse("image", "dtype " + dtype.attr("name").cast<std::string>() +
                        " is not supported: uint8, uint16 (scaled to 0–1), float16 or float32 (float64 is converted)");
  }
  in.height = static_cast<int>(std::min<py::ssize_t>(array.shape(0), std::numeric_limits<int>::max()));
  in.width = static_cast<int>(std::min<py::ssize_t>(array.shape(1), std::numeric_limits<int>::max()));
  in.channels = array.ndim() == 3 ? static_cast<int>(array.shape(2)) : 1;
  check_image_size(array.shape(1), array.shape(0), "image", ImageLimits{});
  return in;
}

// The alpha channel a file of `channels` channels has: the last of grey + alpha and RGBA, as PNG's.
int alpha_of(int channels) { return channels == 2 ? 1 : channels == 4 ? 3 : -1; }

// Integer samples as the PNG reader decodes them (sample_conversion.hpp): colour associated with alpha on the
// integers, then v · (1 / max).
template <typename T>
void integers_to_image(const T* in, Image& image) {
  const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  const std::size_t values = pixels * static_cast<std::size_t>(image.channels);
  if (image.alpha_channel < 0) {
    samples_to_float(in, values, image.pixels.data());
    return;
  }
  std::vector<T> samples(in, in + values);
  associate_alpha(samples.data(), pixels, image.channels, image.alpha_channel);
  samples_to_float(samples.data(), values, image.pixels.data());
}

// Float samples as they are, colour associated with alpha (c·a); InputError for a value that is not finite.
void floats_to_image(const float* in, Image& image) {
  const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  const int channels = image.channels;
  const int alpha = image.alpha_channel;
  float* out = image.pixels.data();
  for (std::size_t p = 0; p < pixels; ++p, in += channels, out += channels) {
    const float a = alpha >= 0 ? in[alpha] : 1.0f;
    for (int c = 0; c < channels; ++c) {
      if (!std::isfinite(in[c])) {
        refuse("image", "holds a value that is not finite at row " + std::to_string(p / image.width) + ", column " +
                            std::to_string(p % image.width));
      }
      out[c] = c == alpha ? in[c] : in[c] * a;
    }
  }
}

Image image_of(const ImageArray& in) {
  Image image(in.width, in.height, in.channels, alpha_of(in.channels));
  switch (in.sample) {
    case Sample::kUint8:
      integers_to_image(static_cast<const std::uint8_t*>(in.array.data()), image);
      break;
    case Sample::kUint16:
      integers_to_image(static_cast<const std::uint16_t*>(in.array.data()), image);
      break;
    case Sample::kFloat32:
      floats_to_image(static_cast<const float*>(in.array.data()), image);
      break;
  }
  return image;
}

// The warped image as the PNG writer stores it (sample_conversion.hpp): quantised, then colour unassociated on the
// integers.
template <typename T>
void image_to_integers(const Image& image, T* out) {
  const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  const std::size_t values = pixels * static_cast<std::size_t>(image.channels);
  for (std::size_t i = 0; i < values; ++i) out[i] = quantise<T>(image.pixels[i]);
  if (image.alpha_channel >= 0) unassociate_alpha(out, pixels, image.channels, image.alpha_channel);
}

// Float pixels with colour unassociated (c / a where 0 < a ≠ 1), as OpenImageIO writes a float file.
void image_to_floats(const Image& image, float* out) {
  const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  const int channels = image.channels;
  const int alpha = image.alpha_channel;
  const float* in = image.pixels.data();
  for (std::size_t p = 0; p < pixels; ++p, in += channels, out += channels) {
    const float a = alpha >= 0 ? in[alpha] : 1.0f;
    const bool divide = a != 0.0f && a != 1.0f;
    for (int c = 0; c < channels; ++c) out[c] = divide && c != alpha ? in[c] / a : in[c];
  }
}

template <typename T>
py::array array_of(const Image& image, bool two_dimensional, void (*convert)(const Image&, T*)) {
  std::vector<py::ssize_t> shape = {image.height, image.width};
  if (!two_dimensional || image.channels != 1) shape.push_back(image.channels);
  py::array_t<T> out(shape);
  convert(image, out.mutable_data());
  return out;
}

py::array array_of(const Image& image, const ImageArray& like) {
  switch (like.sample) {
    case Sample::kUint8:
      return array_of<std::uint8_t>(image, like.two_dimensional, &image_to_integers<std::uint8_t>);
    case Sample::kUint16:
      return array_of<std::uint16_t>(image, like.two_dimensional, &image_to_integers<std::uint16_t>);
    case Sample::kFloat32:
      break;
  }
  return array_of<float>(image, like.two_dimensional, &image_to_floats);
}

int size_argument(const std::optional<int>& value, const char* name) {
  if (value && *value <= 0) refuse(name, "must be > 0, got " + std::to_string(*value));
  return value.value_or(0);
}

int threads_argument(int threads) {
  if (threads < 0) refuse("threads", "must be ≥ 0 (0: all cores), got " + std::to_string(threads));
  return threads;
}

// What a warp did, for return_report: the backend, its certificate (as the CLI's --certificate file), the sampling
// (as a job report's output.sampling) and its durations.
py::dict warp_report(const std::string& backend, bool closed_form, const WarpProblem& problem,
                     const WarpCertificate& certificate, const ImageWarpOptions& options, const ImageWarpTimes& times) {
  proto::CertificateReport cert = certificate_report(certificate);
  if (!closed_form) cert.trajectory = trajectory_report(problem);
  const proto::SamplingReport sampling = sampling_report(options, times.sampling);
  nlohmann::json s = {{"role", proto::to_string(sampling.role)},
                      {"filter", proto::to_string(sampling.filter)},
                      {"footprint_pixels", sampling.footprint_pixels},
                      {"pyramid_levels", sampling.pyramid_levels},
                      {"repaired_normals", sampling.repaired_normals}};
  if (sampling.color_space) s["color_space"] = *sampling.color_space;
  if (sampling.normal_convention) s["normal_convention"] = proto::to_string(*sampling.normal_convention);
  py::dict report;
  report["backend"] = backend;
  report["closed_form"] = closed_form;
  report["certificate"] = to_python(proto::encode_certificate_report(cert));
  report["sampling"] = to_python(s);
  report["timings"] = to_python(nlohmann::json{{"map_s", times.map_s}, {"sampling_s", times.sampling_s}});
  return report;
}

py::object warp_array(const py::object& image, const py::object& features, std::optional<int> width,
                      std::optional<int> height, const std::string& interpolation, const std::string& border,
                      const std::string& filter, const std::optional<std::string>& role,
                      const std::optional<std::string>& color_space, const std::string& normal_convention,
                      double tolerance_px, bool exact, const std::string& backend, int threads,
                      std::optional<double> alpha, const std::optional<std::string>& prealign, bool return_report) {
  return argument_guarded([&]() -> py::object {
    const ImageArray in = image_array(image);
    const proto::WarpSpec spec = decode_features(features, alpha, prealign);
    ImageWarpOptions options;
    options.width = size_argument(width, "width");
    options.height = size_argument(height, "height");
    options.interpolation = proto::parse_enum<Interpolation>(interpolation, InputLocation::flag("interpolation"));
    options.border = proto::parse_enum<Border>(border, InputLocation::flag("border"));
    options.filter = proto::parse_enum<SamplingFilter>(filter, InputLocation::flag("filter"));
    if (!std::isfinite(tolerance_px) || tolerance_px <= 0.0) {
      refuse("tolerance_px", "must be a finite number > 0, got " + std::to_string(tolerance_px));
    }
    options.tolerance_px = tolerance_px;
    options.exact = exact;
    ImageHeader header;
    header.width = in.width;
    header.height = in.height;
    header.channels = in.channels;
    header.alpha_channel = alpha_of(in.channels);
    header.format = in.format;
    const std::optional<ImageRole> chosen_role =
        role ? std::optional(proto::parse_enum<ImageRole>(*role, InputLocation::flag("role"))) : std::nullopt;
    options.encoding = resolve_texture_encoding(
        header, chosen_role, color_space.value_or(""),
        proto::parse_enum<NormalConvention>(normal_convention, InputLocation::flag("normal_convention")),
        InputLocation::flag("role"), InputLocation::flag("color_space"));
    const WarpProblem problem = problem_of(spec, spec.mirror ? in.width : 0);
    const proto::DeviceSpec device = proto::parse_device(backend, InputLocation::flag("backend"));
    RunControl control;
    control.threads = threads_argument(threads);
    Image source = image_of(in);
    Image warped;
    WarpCertificate certificate;
    ImageWarpTimes times;
    std::string backend_name;
    const bool closed_form = has_closed_form(problem);
    {
      py::gil_scoped_release release;
      if (spec.mirror) mirror_image(source);
      // A zero field's warp is its closed form: no device is opened for it (as a job's).
      BackendLease lease(closed_form ? proto::DeviceSpec::cpu() : device);
      backend_name = (*lease).name();
      warped = warp_image(*lease, problem, std::move(source), options, control, &certificate, &times);
    }
    py::array out = array_of(warped, in);
    if (!return_report) return out;
    return py::make_tuple(out, warp_report(backend_name, closed_form, problem, certificate, options, times));
  });
}

py::array map_points_array(const py::object& points, const py::object& features, bool inverse,
                           const std::string& backend, int threads) {
  return argument_guarded([&]() -> py::array {
    py::array_t<double, py::array::c_style | py::array::forcecast> in;
    try {
      in = py::module_::import("numpy").attr("asarray")(points, py::arg("dtype") = "float64");
    } catch (const py::error_already_set& e) {
      refuse("points", std::string("is not an array of numbers: ") + e.what());
    }
    if (in.ndim() != 2 || in.shape(1) != 2) {
      refuse("points", "expected an N×2 array of (x, y) pixel positions, got shape " + shape_text(in));
    }
    const py::ssize_t n = in.shape(0);
    std::vector<Point> mapped;
    mapped.reserve(static_cast<std::size_t>(n));
    const double* xy = in.data();
    for (py::ssize_t i = 0; i < n; ++i) {
      if (!std::isfinite(xy[2 * i]) || !std::isfinite(xy[2 * i + 1])) {
        refuse("points", "row " + std::to_string(i) + " is not finite");
      }
      mapped.emplace_back(xy[2 * i], xy[2 * i + 1]);
    }
    const WarpProblem problem = problem_of(decode_features(features, std::nullopt, std::nullopt), 0);
    const proto::DeviceSpec device = proto::parse_device(backend, InputLocation::flag("backend"));
    RunControl control;
    control.threads = threads_argument(threads);
    {
      py::gil_scoped_release release;
      BackendLease lease(device);
      map_points(*lease, problem, mapped, inverse ? Direction::kInverse : Direction::kForward, control);
    }
    py::array_t<double> out({n, py::ssize_t{2}});
    double* o = out.mutable_data();
    for (py::ssize_t i = 0; i < n; ++i) {
      o[2 * i] = mapped[static_cast<std::size_t>(i)].real();
      o[2 * i + 1] = mapped[static_cast<std::size_t>(i)].imag();
    }
    return out;
  });
}

}  // namespace

void register_array_functions(py::module_& module) {
  module.def("warp", &warp_array, py::arg("image"), py::arg("features"), py::kw_only(), py::arg("width") = py::none(),
             py::arg("height") = py::none(), py::arg("interpolation") = "bilinear", py::arg("border") = "transparent",
             py::arg("filter") = "footprint", py::arg("role") = py::none(), py::arg("color_space") = py::none(),
             py::arg("normal_convention") = "opengl", py::arg("tolerance_px") = 0.05, py::arg("exact") = false,
             py::arg("backend") = runner::default_device(), py::arg("threads") = 0, py::arg("alpha") = py::none(),
             py::arg("prealign") = py::none(), py::arg("return_report") = false,
             "Warps an image array (H×W or H×W×C, C ≤ 4; uint8, uint16, float16, float32) so that each feature's "
             "source lands on its target: a new array of its dtype (float32 for floats), as `texwarp warp` would "
             "write and a reader read back. With return_report: (array, report dict).");
  module.def("map_points", &map_points_array, py::arg("points"), py::arg("features"), py::kw_only(),
             py::arg("inverse") = false, py::arg("backend") = runner::default_device(), py::arg("threads") = 0,
             "Maps an N×2 array of pixel positions through the warp f (or f⁻¹ with inverse=True), as `texwarp map`: "
             "an N×2 float64 array.");
}

}  // namespace texwarp::python
