// Roles' decoding before and encoding after a warp's resampling: see texture_encoding.hpp.
#include "texwarp/core/texture_encoding.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <utility>
#include <vector>

#include "texwarp/core/footprint_sampler.hpp"
#include "texwarp/core/image_module.hpp"
#include "texwarp/core/parallel_chunks.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

// A normal's z below this (after the repair) is raised to it: its slope n_xy / n_z stays finite.
constexpr double kMinNormalZ = 1e-3;
// A stored normal shorter than this, or with z below −kNormalZTolerance (more than an 8-bit step under the
// surface), is invalid: repaired and counted.
constexpr double kMinNormalLength = 0.1;
constexpr double kNormalZTolerance = 2.0 / 255.0;

bool is_float_format(PixelFormat f) { return f == PixelFormat::kHalf || f == PixelFormat::kFloat; }

// The colour channels of a pixel: every channel but alpha.
template <typename F>
void for_colour_channels(Image& image, std::size_t pixel, F&& f) {
  float* px = image.pixels.data() + pixel * static_cast<std::size_t>(image.channels);
  const float a = image.alpha_channel >= 0 ? px[image.alpha_channel] : 1.0f;
  for (int c = 0; c < image.channels; ++c) {
    if (c != image.alpha_channel) f(px[c], a);
  }
}

// Applies `transfer` to the colour channels of rows [y0, y1), on unassociated values (alpha stays associated).
template <typename Transfer>
void transfer_rows(Image& image, int y0, int y1, Transfer&& transfer) {
  const std::size_t begin = static_cast<std::size_t>(y0) * image.width;
  const std::size_t end = static_cast<std::size_t>(y1) * image.width;
  for (std::size_t i = begin; i < end; ++i) {
    for_colour_channels(image, i, [&](float& v, float a) {
      if (a <= 0.0f) {
        v = 0.0f;
      } else if (a == 1.0f) {
        v = transfer(v);
      } else {
        v = transfer(v / a) * a;
      }
    });
  }
}

// The first three colour channels (the normal's x, y, z), skipping alpha.
std::array<int, 3> normal_channels(const Image& image) {
  std::array<int, 3> ch{};
  int n = 0;
  for (int c = 0; c < image.channels && n < 3; ++c) {
    if (c != image.alpha_channel) ch[static_cast<std::size_t>(n++)] = c;
  }
  return ch;
}

// The working space of a colour image in a named (OpenColorIO) space: its config's scene-linear role.
constexpr const char* kSceneLinearRole = "scene_linear";

// Converts rows [y0, y1) of `image` between colour spaces through the image module (OpenColorIO), on unassociated
// colour; InputError at `where` when the module does not know a name.
void convert_rows(Image& image, int y0, int y1, const std::string& from, const std::string& to,
                  const InputLocation& where) {
  const TexwarpImageModule& module = image_module("converting colour space \"" + from + "\"", "");
  const std::size_t begin = static_cast<std::size_t>(y0) * image.width;
  const std::size_t count = static_cast<std::size_t>(y1 - y0) * image.width;
  const auto c = static_cast<std::size_t>(image.channels);
  float* first = image.pixels.data() + begin * c;
  const int alpha = image.alpha_channel;
  if (alpha >= 0) {
    for (std::size_t i = 0; i < count; ++i) {
      float* px = first + i * c;
      for (int ch = 0; ch < image.channels; ++ch) {
        if (ch != alpha) px[ch] = px[alpha] > 0.0f ? px[ch] / px[alpha] : 0.0f;
      }
    }
  }
  TexwarpImageMessage message{};
  if (module.convert_colors(from.c_str(), to.c_str(), first, count, image.channels, alpha, &message) !=
      TEXWARP_IMAGE_OK) {
    throw InputError(where, message.text);
  }
  if (alpha >= 0) {
    for (std::size_t i = 0; i < count; ++i) {
      float* px = first + i * c;
      for (int ch = 0; ch < image.channels; ++ch) {
        if (ch != alpha) px[ch] *= px[alpha];
      }
    }
  }
}

// The sRGB transfer functions by table, for the passes over every pixel: decoding reads a 16-bit code's value from a
// 65536-entry table when the value is one (8-bit codes are 257 × theirs), the formula otherwise; encoding
// interpolates a 65536-interval table of [0, 1] (error below 1e-7, far under a 16-bit step), the formula outside.
constexpr int kTableSteps = 65535;

const std::vector<float>& decode_table() {
  static const std::vector<float> kTable = [] {
    std::vector<float> t(kTableSteps + 1);
    for (int i = 0; i <= kTableSteps; ++i)
      t[static_cast<std::size_t>(i)] = srgb_to_linear(static_cast<float>(i) / kTableSteps);
    return t;
  }();
  return kTable;
}

const std::vector<float>& encode_table() {
  static const std::vector<float> kTable = [] {
    std::vector<float> t(kTableSteps + 2);
    for (int i = 0; i <= kTableSteps; ++i) {
      t[static_cast<std::size_t>(i)] =
          static_cast<float>(linear_to_srgb(static_cast<float>(static_cast<double>(i) / kTableSteps)));
    }
    t[kTableSteps + 1] = t[kTableSteps];
    return t;
  }();
  return kTable;
}

float srgb_to_linear_fast(float v) {
  const float scaled = v * static_cast<float>(kTableSteps);
  if (scaled >= 0.0f && scaled <= static_cast<float>(kTableSteps)) {
    // scaled is in [0, 65535]: + 0.5 and truncation round it, without std::lround's call on this per-pixel path.
    const auto code = static_cast<std::size_t>(scaled + 0.5f);  // NOLINT(bugprone-incorrect-roundings)
    if (std::abs(scaled - static_cast<float>(code)) < 1e-3f) return decode_table()[code];
  }
  return srgb_to_linear(v);
}

float linear_to_srgb_fast(float v) {
  if (!(v >= 0.0f && v <= 1.0f)) return linear_to_srgb(v);
  const float scaled = v * static_cast<float>(kTableSteps);
  const auto i = static_cast<std::size_t>(scaled);
  const float f = scaled - static_cast<float>(i);
  const std::vector<float>& t = encode_table();
  return t[i] + f * (t[i + 1] - t[i]);
}

// Whether the colour config (OpenColorIO's $OCIO, else OpenImageIO's built-in one) converts `name` to scene-linear
// and back as a colour space does: grey levels 0 < 0.18 < 0.5 < 1 to rising finite values, and those back to rising
// finite values (OpenImageIO's built-in config also takes "GammaCorrected0" or "gamma-1", which would turn every
// pixel into 1 or ∞). Else false, with the reason in `message`.
bool config_knows(const std::string& name, const std::string& what, std::string* message) {
  const TexwarpImageModule& module = image_module(what, "");
  constexpr std::array<float, 4> kGreys = {0.0f, 0.18f, 0.5f, 1.0f};
  std::array<float, 3 * kGreys.size()> probe{};
  for (std::size_t i = 0; i < probe.size(); ++i) probe[i] = kGreys[i / 3];
  const auto rising = [&probe] {
    for (std::size_t i = 0; i < probe.size(); ++i) {
      if (!std::isfinite(probe[i]) || (i >= 3 && !(probe[i] > probe[i - 3]))) return false;
    }
    return true;
  };
  for (const auto& [from, to] :
       {std::pair{name.c_str(), kSceneLinearRole}, std::pair{kSceneLinearRole, name.c_str()}}) {
    TexwarpImageMessage m{};
    if (module.convert_colors(from, to, probe.data(), kGreys.size(), 3, -1, &m) != TEXWARP_IMAGE_OK) {
      if (message) *message = m.text;
      return false;
    }
    if (!rising()) {
      if (message) {
        *message =
            "it does not take the greys 0 < 0.18 < 0.5 < 1 to rising finite values and back, as a colour space does";
      }
      return false;
    }
  }
  return true;
}

bool is_named(const TextureEncoding& encoding) {
  return encoding.role == ImageRole::kColor && encoding.color_space != kSrgbColorSpace &&
         encoding.color_space != kLinearColorSpace;
}

}  // namespace

float srgb_to_linear(float v) {
  if (v <= 0.04045f) return v / 12.92f;
  return std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float v) {
  if (v <= 0.0031308f) return v * 12.92f;
  return 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

TextureEncoding resolve_texture_encoding(const ImageHeader& header, std::optional<ImageRole> role,
                                         const std::string& color_space, NormalConvention convention,
                                         const InputLocation& where_role, const InputLocation& where_color_space) {
  // What the file declares: a built-in name, or a colour space the colour config knows (a texture texwarp wrote
  // for an OpenColorIO space records it); a name neither knows leaves the file's defaults. A declared space is data
  // when it is one of the built-in data names or the config marks it so (its isdata, whatever its name).
  std::optional<std::string> declared;
  bool declared_data = proto::is_data_color_space(header.color_space);
  if (!header.color_space.empty()) {
    declared = proto::canonical_color_space(header.color_space);
    const std::string what = "the file's colour space \"" + header.color_space + "\"";
    if (!declared && config_knows(header.color_space, what, nullptr)) {
      declared = header.color_space;
      declared_data = image_module(what, "").is_data_color_space(header.color_space.c_str()) != 0;
    }
  }
  std::optional<std::string> asked;
  if (!color_space.empty()) {
    asked = proto::canonical_color_space(color_space);
    if (!asked) {
      // A name the colour config may know: checked now, before any pixel is decoded.
      std::string message;
      if (!config_knows(color_space, "the colour space \"" + color_space + "\"", &message)) {
        throw InputError(where_color_space, "unknown colour space \"" + color_space.substr(0, 80) + "\": expected " +
                                                proto::quoted_color_space_names() +
                                                ", or a space of OpenColorIO's config (" + message + ")");
      }
      asked = color_space;
    }
  }
  TextureEncoding encoding;
  encoding.normal_convention = convention;
  if (role) {
    encoding.role = *role;
  } else if (asked) {
    encoding.role = ImageRole::kColor;  // a colour space was named: the image is colour
  } else if (declared) {
    encoding.role = declared_data                                                       ? ImageRole::kData
                    : *declared != kLinearColorSpace || !is_float_format(header.format) ? ImageRole::kColor
                                                                                        : ImageRole::kData;
  } else {
    encoding.role = is_float_format(header.format) ? ImageRole::kData : ImageRole::kColor;
  }
  if (encoding.role == ImageRole::kColor) {
    encoding.color_space = asked ? *asked
                           : declared
                               ? *declared
                               : std::string(is_float_format(header.format) ? kLinearColorSpace : kSrgbColorSpace);
  }
  if (encoding.role == ImageRole::kNormal) {
    const int colour = header.channels - (header.alpha_channel >= 0 ? 1 : 0);
    if (colour < 3) {
      throw InputError(where_role, "a normal map needs three colour channels (x, y, z as RGB); the image has " +
                                       std::to_string(colour));
    }
  }
  return encoding;
}

bool decodes_values(const TextureEncoding& encoding) {
  return encoding.role == ImageRole::kNormal ||
         (encoding.role == ImageRole::kColor && encoding.color_space != kLinearColorSpace);
}

void decode_texture(Image& image, const TextureEncoding& encoding, const RunControl& control,
                    TextureDecodeStats& stats) {
  if (!decodes_values(encoding)) return;
  if (is_named(encoding)) {
    for_each_row_band(image.height, control, [&](int y0, int y1) {
      convert_rows(image, y0, y1, encoding.color_space, kSceneLinearRole, InputLocation::flag("--colorspace"));
    });
    return;
  }
  if (encoding.role == ImageRole::kColor) {
    for_each_row_band(image.height, control,
                      [&](int y0, int y1) { transfer_rows(image, y0, y1, srgb_to_linear_fast); });
    return;
  }
  const auto ch = normal_channels(image);
  const double green = encoding.normal_convention == NormalConvention::kOpenGl ? -1.0 : 1.0;
  std::atomic<std::size_t> repaired{0};
  for_each_row_band(image.height, control, [&](int y0, int y1) {
    std::size_t local = 0;
    for (std::size_t i = static_cast<std::size_t>(y0) * image.width; i < static_cast<std::size_t>(y1) * image.width;
         ++i) {
      float* px = image.pixels.data() + i * static_cast<std::size_t>(image.channels);
      const float a = image.alpha_channel >= 0 ? px[image.alpha_channel] : 1.0f;
      if (a <= 0.0f) {
        px[ch[0]] = px[ch[1]] = px[ch[2]] = 0.0f;
        continue;
      }
      double x = 2.0 * px[ch[0]] / a - 1.0;
      double y = green * (2.0 * px[ch[1]] / a - 1.0);
      double z = 2.0 * px[ch[2]] / a - 1.0;
      double length = std::sqrt(x * x + y * y + z * z);
      if (!(length >= kMinNormalLength) || !(z >= -kNormalZTolerance) || !std::isfinite(length)) {
        ++local;
        if (!(length >= kMinNormalLength) || !std::isfinite(length)) {
          x = y = 0.0;
          z = 1.0;
        }
      }
      z = std::max(z, kMinNormalZ * std::max(length, 1e-12));
      length = std::sqrt(x * x + y * y + z * z);
      px[ch[0]] = static_cast<float>(a * x / length);
      px[ch[1]] = static_cast<float>(a * y / length);
      px[ch[2]] = static_cast<float>(a * z / length);
    }
    repaired += local;
  });
  stats.repaired_normals += repaired.load();
}

void encode_texture(Image& image, const TextureEncoding& encoding, const std::vector<Point>& positions,
                    const RunControl& control) {
  if (encoding.role == ImageRole::kData) return;
  if (is_named(encoding)) {
    for_each_row_band(image.height, control, [&](int y0, int y1) {
      convert_rows(image, y0, y1, kSceneLinearRole, encoding.color_space, InputLocation::flag("--colorspace"));
    });
    return;
  }
  if (encoding.role == ImageRole::kColor) {
    if (encoding.color_space != kSrgbColorSpace) return;
    for_each_row_band(image.height, control,
                      [&](int y0, int y1) { transfer_rows(image, y0, y1, linear_to_srgb_fast); });
    return;
  }
  // Normals: with h' = h ∘ f⁻¹, ∇h' = Kᵀ ∇h (K the inverse map's Jacobian, source pixels per output pixel), so the
  // slope n_xy / n_z turns and scales by Kᵀ: the normals that heights warped with the texture give, derived again on
  // the output's pixels.
  const auto ch = normal_channels(image);
  const double green = encoding.normal_convention == NormalConvention::kOpenGl ? -1.0 : 1.0;
  for_each_row_band(image.height, control, [&](int y0, int y1) {
    for (int yy = y0; yy < y1; ++yy) {
      for (int xx = 0; xx < image.width; ++xx) {
        float* px = image.pixel(xx, yy);
        const double a = image.alpha_channel >= 0 ? px[image.alpha_channel] : 1.0;
        if (a <= 0.0) continue;
        const double x = px[ch[0]] / a;
        const double y = px[ch[1]] / a;
        const double length = std::sqrt(x * x + y * y + double(px[ch[2]] / a) * (px[ch[2]] / a));
        if (!(length > 1e-6)) {  // normals that cancelled out in the filter: the surface's own
          px[ch[0]] = px[ch[1]] = static_cast<float>(a * 0.5);
          px[ch[2]] = static_cast<float>(a);
          continue;
        }
        const double z = std::max(double(px[ch[2]] / a), kMinNormalZ * length);
        const PixelJacobian k = grid_jacobian(positions, image.width, image.height, xx, yy);
        const Point kx = k.dx;
        const Point ky = k.dy;
        const double gx = x / z;
        const double gy = y / z;
        const double tx = kx.real() * gx + kx.imag() * gy;  // Kᵀ g
        const double ty = ky.real() * gx + ky.imag() * gy;
        const double norm = std::sqrt(tx * tx + ty * ty + 1.0);
        const double nx = tx / norm;
        const double ny = green * ty / norm;
        const double nz = 1.0 / norm;
        px[ch[0]] = static_cast<float>(a * 0.5 * (nx + 1.0));
        px[ch[1]] = static_cast<float>(a * 0.5 * (ny + 1.0));
        px[ch[2]] = static_cast<float>(a * 0.5 * (nz + 1.0));
      }
    }
  });
}

}  // namespace texwarp
