// Roles (texture_encoding.hpp) against closed forms: an sRGB checker averaged in linear light, a normal map turned
// with the texture, a sheared normal map against the normals of the sheared height field it came from, invalid
// normals repaired and counted, and each file's default role and colour space.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "input_error_text.hpp"
#include "texwarp/core/footprint_sampler.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/core/texture_encoding.hpp"

namespace texwarp {
namespace {

using testing::input_error_of;

TextureEncoding colour(const char* space) { return {ImageRole::kColor, space, NormalConvention::kOpenGl}; }
TextureEncoding normals(NormalConvention convention = NormalConvention::kOpenGl) {
  return {ImageRole::kNormal, "", convention};
}

// The inverse map q ↦ K·q + b at every pixel centre (K given by its columns).
std::vector<Point> affine_positions(int width, int height, Point kx, Point ky, Point b) {
  std::vector<Point> p;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) p.push_back((x + 0.5) * kx + (y + 0.5) * ky + b);
  }
  return p;
}

double angle_deg(const double a[3], const double b[3]) {
  const double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const double na = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const double nb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  return std::acos(std::clamp(dot / (na * nb), -1.0, 1.0)) * 180.0 / std::numbers::pi;
}

// A normal in image coordinates (x right, y down) stored as an OpenGL normal map texel: green = −y.
void store_normal(float* px, double x, double y, double z) {
  const double n = std::sqrt(x * x + y * y + z * z);
  px[0] = static_cast<float>(0.5 * (x / n + 1.0));
  px[1] = static_cast<float>(0.5 * (-y / n + 1.0));
  px[2] = static_cast<float>(0.5 * (z / n + 1.0));
}
void load_normal(const float* px, double n[3]) {
  n[0] = 2.0 * px[0] - 1.0;
  n[1] = -(2.0 * px[1] - 1.0);
  n[2] = 2.0 * px[2] - 1.0;
}

TEST(TextureEncoding, SrgbCheckerMinifiedTwiceAveragesLightNotCodes) {
  Image checker(64, 64, 3);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      for (int c = 0; c < 3; ++c) checker.pixel(x, y)[c] = static_cast<float>((x + y) % 2);
    }
  }
  const auto positions = affine_positions(32, 32, Point(2, 0), Point(0, 2), Point(0, 0));
  const SamplingOptions sampling{Interpolation::kBilinear, Border::kClamp};
  const Image linear_light = resample_image(checker, positions, 32, 32, sampling, colour(kSrgbColorSpace));
  const Image codes = resample_image(checker, positions, 32, 32, sampling, TextureEncoding{});
  for (int y = 1; y < 31; ++y) {
    for (int x = 1; x < 31; ++x) {
      EXPECT_EQ(std::lround(linear_light.pixel(x, y)[0] * 255.0f), 188) << x << "," << y;  // sRGB of light 0.5
      EXPECT_NEAR(codes.pixel(x, y)[1], 0.5f, 1e-6);
    }
  }
}

TEST(TextureEncoding, SrgbRoundTripKeepsEveryEightBitCodeAndAssociatedAlpha) {
  Image image(256, 1, 2, 1);
  for (int x = 0; x < 256; ++x) {
    const float a = (x % 5 == 0) ? 1.0f : 0.6f;
    image.pixel(x, 0)[0] = (static_cast<float>(x) / 255.0f) * a;
    image.pixel(x, 0)[1] = a;
  }
  TextureDecodeStats stats;
  Image linear = image;
  decode_texture(linear, colour(kSrgbColorSpace), {}, stats);
  EXPECT_NEAR(linear.pixel(128, 0)[0] / linear.pixel(128, 0)[1], srgb_to_linear(128 / 255.0f), 1e-6);
  EXPECT_EQ(linear.pixel(7, 0)[1], 0.6f);  // alpha untouched
  encode_texture(linear, colour(kSrgbColorSpace), std::vector<Point>(256, Point()), {});
  for (int x = 0; x < 256; ++x) {
    EXPECT_EQ(std::lround(linear.pixel(x, 0)[0] / linear.pixel(x, 0)[1] * 255.0f), x);
  }
  EXPECT_FALSE(decodes_values(colour(kLinearColorSpace)));  // filtered as it is
  Image untouched = image;
  decode_texture(untouched, colour(kLinearColorSpace), {}, stats);
  EXPECT_EQ(untouched.pixels, image.pixels);
  EXPECT_NEAR(srgb_to_linear(0.5f), 0.214041f, 1e-6);
  EXPECT_NEAR(linear_to_srgb(0.5f), 0.735357f, 1e-6);
}

TEST(TextureEncoding, TheTabulatedTransferFunctionsMatchTheFormulas) {
  // Every 8- and 16-bit code, and values between codes and outside [0, 1], decoded and encoded by the passes.
  std::vector<float> values;
  for (int i = 0; i <= 65535; ++i) values.push_back(static_cast<float>(i) / 65535.0f);
  for (int i = 0; i <= 255; ++i) values.push_back(static_cast<float>(i) / 255.0f);
  for (int i = 0; i < 20000; ++i) values.push_back(static_cast<float>(std::fmod(i * 0.6180339887, 1.0)));
  for (const float v : {-0.25f, 1.0f + 1e-6f, 1.5f, 3.0f}) values.push_back(v);
  Image image(static_cast<int>(values.size()), 1, 1);
  image.pixels = values;
  TextureDecodeStats stats;
  Image decoded = image;
  decode_texture(decoded, colour(kSrgbColorSpace), {}, stats);
  Image encoded = image;
  encode_texture(encoded, colour(kSrgbColorSpace), std::vector<Point>(values.size()), {});
  double worst_decode = 0.0;
  double worst_encode = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    worst_decode = std::max(worst_decode, std::abs(double(decoded.pixels[i]) - srgb_to_linear(values[i])));
    worst_encode = std::max(worst_encode, std::abs(double(encoded.pixels[i]) - linear_to_srgb(values[i])));
  }
  EXPECT_LT(worst_decode, 2e-7);
  EXPECT_LT(worst_encode, 2e-6);  // under a 16-bit step (1.5e-5)
}

TEST(TextureEncoding, NormalMapTurnsWithTheTexture) {
  // A constant normal tilted toward +x (image coordinates), the texture rotated by θ about its centre: the output's
  // tangent part is the input's turned by θ, its z unchanged.
  Image map(64, 64, 3);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) store_normal(map.pixel(x, y), 0.5, 0.2, 1.0);
  }
  for (const double degrees : {90.0, 30.0, -120.0}) {
    const double theta = degrees * std::numbers::pi / 180;
    const Point inverse = std::polar(1.0, -theta);  // f⁻¹(q) = e^{−iθ}(q − c) + c
    const Point c(32, 32);
    const auto positions = affine_positions(64, 64, inverse, inverse * Point(0, 1), c - inverse * c);
    for (const auto convention : {NormalConvention::kOpenGl, NormalConvention::kDirectX}) {
      Image source = map;
      if (convention == NormalConvention::kDirectX) {
        for (int i = 0; i < 64 * 64; ++i) source.pixels[3 * i + 1] = 1.0f - source.pixels[3 * i + 1];
      }
      const Image out = resample_image(source, positions, 64, 64,
                                       SamplingOptions{Interpolation::kBilinear, Border::kClamp}, normals(convention));
      const Point turned = std::polar(1.0, theta) * Point(0.5, 0.2);
      const double expected[3] = {turned.real(), turned.imag(), 1.0};
      double worst = 0.0;
      double worst_unturned = 0.0;
      const double unturned[3] = {0.5, 0.2, 1.0};
      for (int y = 8; y < 56; ++y) {
        for (int x = 8; x < 56; ++x) {
          float px[3] = {out.pixel(x, y)[0], out.pixel(x, y)[1], out.pixel(x, y)[2]};
          if (convention == NormalConvention::kDirectX) px[1] = 1.0f - px[1];
          double n[3];
          load_normal(px, n);
          worst = std::max(worst, angle_deg(n, expected));
          worst_unturned = std::max(worst_unturned, angle_deg(n, unturned));
        }
      }
      EXPECT_LT(worst, 0.05) << degrees;
      EXPECT_GT(worst_unturned, 10.0) << degrees;  // as colour it would have kept its direction
    }
  }
}

TEST(TextureEncoding, ShearedNormalMapAgreesWithTheNormalsOfTheShearedHeights) {
  // h(x, y) = 3 sin(x / 9) cos(y / 13); the normal map n ∝ (−∇h, 1). Under the inverse map q ↦ K·q + b the warped
  // heights are h(K·q + b), whose gradient is Kᵀ ∇h(K·q + b): their normals, in closed form and by central
  // differences of the warped height image, against the warped normal map.
  const int n = 192;
  Image heights(n, n, 1);
  Image map(n, n, 3);
  const auto h = [](double x, double y) { return 3.0 * std::sin(x / 9.0) * std::cos(y / 13.0); };
  const auto grad = [](double x, double y) {
    return Point(3.0 / 9.0 * std::cos(x / 9.0) * std::cos(y / 13.0),
                 -3.0 / 13.0 * std::sin(x / 9.0) * std::sin(y / 13.0));
  };
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      heights.pixel(x, y)[0] = static_cast<float>(h(x + 0.5, y + 0.5));
      const Point g = grad(x + 0.5, y + 0.5);
      store_normal(map.pixel(x, y), -g.real(), -g.imag(), 1.0);
    }
  }
  const Point kx(1.3, 0.1);  // K's columns: a shear that minifies along one axis and magnifies along the other
  const Point ky(0.4, 0.8);
  const Point b(10, 12);
  const int m = 96;
  const auto positions = affine_positions(m, m, kx, ky, b);
  const SamplingOptions sampling{Interpolation::kBicubic, Border::kClamp};
  const Image warped_map = resample_image(map, positions, m, m, sampling, normals());
  const Image warped_heights = resample_image(heights, positions, m, m, sampling, TextureEncoding{});
  double worst_closed = 0.0;
  double worst_derived = 0.0;
  double worst_as_colour = 0.0;
  const Image as_colour = resample_image(map, positions, m, m, sampling, TextureEncoding{});
  for (int y = 4; y < m - 4; ++y) {
    for (int x = 4; x < m - 4; ++x) {
      const Point p = positions[static_cast<std::size_t>(y) * m + x];
      const Point g = grad(p.real(), p.imag());
      const double gx = kx.real() * g.real() + kx.imag() * g.imag();  // Kᵀ ∇h
      const double gy = ky.real() * g.real() + ky.imag() * g.imag();
      const double closed[3] = {-gx, -gy, 1.0};
      const double dx = 0.5 * (warped_heights.pixel(x + 1, y)[0] - warped_heights.pixel(x - 1, y)[0]);
      const double dy = 0.5 * (warped_heights.pixel(x, y + 1)[0] - warped_heights.pixel(x, y - 1)[0]);
      const double derived[3] = {-dx, -dy, 1.0};
      double got[3];
      load_normal(warped_map.pixel(x, y), got);
      double old[3];
      load_normal(as_colour.pixel(x, y), old);
      worst_closed = std::max(worst_closed, angle_deg(got, closed));
      worst_derived = std::max(worst_derived, angle_deg(got, derived));
      worst_as_colour = std::max(worst_as_colour, angle_deg(old, closed));
    }
  }
  std::printf("sheared normal map: worst angle %.3f° against closed form, %.3f° against re-derived heights; "
              "%.2f° as colour\n",
              worst_closed, worst_derived, worst_as_colour);
  EXPECT_LT(worst_closed, 1.0);
  EXPECT_LT(worst_derived, 1.5);
  EXPECT_GT(worst_as_colour, 5.0);
}

TEST(TextureEncoding, ANamedSpaceGoesThroughOpenColorIo) {
  // OpenImageIO's built-in config ($OCIO unset here) knows Rec709: its inverse OETF against the formula, and back.
  ASSERT_EQ(std::getenv("OCIO"), nullptr);
  ImageHeader png;
  png.channels = 3;
  const TextureEncoding rec709 =
      resolve_texture_encoding(png, std::nullopt, "Rec709", NormalConvention::kOpenGl, InputLocation::flag("--in"),
                               InputLocation::flag("--colorspace"));
  EXPECT_EQ(rec709.role, ImageRole::kColor);
  EXPECT_EQ(rec709.color_space, "Rec709");
  EXPECT_TRUE(decodes_values(rec709));
  Image image(3, 1, 3);
  const float codes[3] = {0.05f, 0.5f, 0.9f};
  for (int x = 0; x < 3; ++x) image.pixel(x, 0)[0] = image.pixel(x, 0)[1] = image.pixel(x, 0)[2] = codes[x];
  TextureDecodeStats stats;
  Image linear = image;
  decode_texture(linear, rec709, {}, stats);
  for (int x = 0; x < 3; ++x) {
    const double v = codes[x];
    const double expected = v < 0.081 ? v / 4.5 : std::pow((v + 0.099) / 1.099, 1.0 / 0.45);
    EXPECT_NEAR(linear.pixel(x, 0)[1], expected, 2e-4) << v;
  }
  encode_texture(linear, rec709, std::vector<Point>(3), {});
  for (int x = 0; x < 3; ++x) EXPECT_NEAR(linear.pixel(x, 0)[2], codes[x], 1e-4);
}

TEST(TextureEncoding, InvalidNormalsAreRepairedAndCounted) {
  Image map(4, 1, 3);
  store_normal(map.pixel(0, 0), 0, 0, 1);
  map.pixel(1, 0)[0] = map.pixel(1, 0)[1] = map.pixel(1, 0)[2] = 0.5f;  // zero length
  store_normal(map.pixel(2, 0), 0.3, 0.1, -0.8);                        // below the surface
  store_normal(map.pixel(3, 0), 1.0, 0.0, 0.0);                         // grazing: valid
  TextureDecodeStats stats;
  Image decoded = map;
  decode_texture(decoded, normals(), {}, stats);
  EXPECT_EQ(stats.repaired_normals, 2u);
  EXPECT_FLOAT_EQ(decoded.pixel(1, 0)[2], 1.0f);  // the surface's own normal
  EXPECT_GT(decoded.pixel(2, 0)[2], 0.0f);
  for (int x = 0; x < 4; ++x) {
    const float* n = decoded.pixel(x, 0);
    EXPECT_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0, 1e-5) << x;
  }
}

TEST(TextureEncoding, DefaultsFollowTheFileAndFlagsOverride) {
  const InputLocation role_flag = InputLocation::flag("--in");
  const InputLocation space_flag = InputLocation::flag("--colorspace");
  ImageHeader png;
  png.channels = 3;
  png.format = PixelFormat::kUint8;
  auto resolved = resolve_texture_encoding(png, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag);
  EXPECT_EQ(resolved.role, ImageRole::kColor);
  EXPECT_EQ(resolved.color_space, "sRGB");
  ImageHeader exr = png;
  exr.format = PixelFormat::kHalf;
  resolved = resolve_texture_encoding(exr, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag);
  EXPECT_EQ(resolved.role, ImageRole::kData);
  exr.color_space = "sRGB";  // a float file that says it is sRGB
  resolved = resolve_texture_encoding(exr, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag);
  EXPECT_EQ(resolved.role, ImageRole::kColor);
  EXPECT_EQ(resolved.color_space, "sRGB");
  ImageHeader tx = png;
  tx.color_space = "Raw";  // what texwarp records for a data or normal map's texture (Blender: "Non-Color")
  resolved = resolve_texture_encoding(tx, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag);
  EXPECT_EQ(resolved.role, ImageRole::kData);
  EXPECT_EQ(resolved.color_space, "");
  tx.color_space = "Non-Color";
  EXPECT_EQ(resolve_texture_encoding(tx, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag).role,
            ImageRole::kData);
  tx.color_space = "Utility - Raw";  // ACES 1.x configs' name
  EXPECT_EQ(resolve_texture_encoding(tx, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag).role,
            ImageRole::kData);
  // A space the colour config knows (OpenImageIO's built-in config knows Rec709) is the input's space and colour,
  // in a float file too; a name it does not know leaves the file's defaults.
  ImageHeader declared = exr;
  declared.color_space = "Rec709";
  resolved = resolve_texture_encoding(declared, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag);
  EXPECT_EQ(resolved.role, ImageRole::kColor);
  EXPECT_EQ(resolved.color_space, "Rec709");
  EXPECT_TRUE(decodes_values(resolved));
  // Unknown to the config, or known but not a colour space (the built-in config reads "GammaCorrected0" as the
  // power 0, which would make every pixel 1): the defaults.
  for (const char* name : {"KodakLog", "GammaCorrected0", "GammaCorrected-1"}) {
    declared.color_space = name;
    resolved = resolve_texture_encoding(declared, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag);
    EXPECT_EQ(resolved.role, ImageRole::kData) << name;
  }
  EXPECT_THAT(input_error_of([&] {
                resolve_texture_encoding(png, std::nullopt, "GammaCorrected0", NormalConvention::kOpenGl, role_flag,
                                         space_flag);
              }),
              ::testing::HasSubstr("unknown colour space \"GammaCorrected0\": expected \"sRGB\" or \"linear\", or a "
                                   "space of OpenColorIO's config (it does not take the greys 0 < 0.18 < 0.5 < 1 to "
                                   "rising finite values and back"));
  resolved = resolve_texture_encoding(png, std::nullopt, "GammaCorrected1.8", NormalConvention::kOpenGl, role_flag,
                                      space_flag);
  EXPECT_EQ(resolved.color_space, "GammaCorrected1.8");
  declared.format = PixelFormat::kUint16;
  resolved = resolve_texture_encoding(declared, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag);
  EXPECT_EQ(resolved.role, ImageRole::kColor);
  EXPECT_EQ(resolved.color_space, "sRGB");
  resolved = resolve_texture_encoding(declared, std::nullopt, "linear", NormalConvention::kOpenGl, role_flag,
                                      space_flag);  // the flag overrides
  EXPECT_EQ(resolved.color_space, "linear");
  png.color_space = "Linear";  // a 16-bit PNG with gAMA 1.0
  resolved = resolve_texture_encoding(png, std::nullopt, "", NormalConvention::kOpenGl, role_flag, space_flag);
  EXPECT_EQ(resolved.color_space, "linear");
  resolved =
      resolve_texture_encoding(png, std::nullopt, "srgb_texture", NormalConvention::kOpenGl, role_flag, space_flag);
  EXPECT_EQ(resolved.color_space, "sRGB");
  resolved = resolve_texture_encoding(png, ImageRole::kNormal, "", NormalConvention::kDirectX, role_flag, space_flag);
  EXPECT_EQ(resolved.role, ImageRole::kNormal);
  EXPECT_EQ(resolved.color_space, "");
  EXPECT_THAT(
      input_error_of([&] {
        resolve_texture_encoding(png, std::nullopt, "ACEScg", NormalConvention::kOpenGl, role_flag, space_flag);
      }),
      ::testing::StartsWith("--colorspace: unknown colour space \"ACEScg\": expected \"sRGB\" or \"linear\", or a "
                            "space of OpenColorIO's config (no conversion from colour space \"ACEScg\""));
  ImageHeader grey = png;
  grey.channels = 2;
  grey.alpha_channel = 1;
  EXPECT_EQ(input_error_of([&] {
              resolve_texture_encoding(grey, ImageRole::kNormal, "", NormalConvention::kOpenGl, role_flag, space_flag);
            }),
            "--in: a normal map needs three colour channels (x, y, z as RGB); the image has 1");
}

}  // namespace
}  // namespace texwarp
