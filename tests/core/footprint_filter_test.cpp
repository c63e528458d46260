// Footprint filtering (footprint_sampler.hpp) on warps whose right answer is known in closed form: similarity
// minifications against the source averaged exactly over each output pixel's footprint, the plain reconstruction
// kept value for value where the map does not minify, and the footprint's axes from the grid's differences.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "texwarp/core/footprint_sampler.hpp"
#include "texwarp/core/image_warp.hpp"

namespace texwarp {
namespace {

// A zone plate: cos(π r² / n), its local frequency r / n cycles per pixel, reaching 0.5 (Nyquist) at r = n / 2.
Image zone_plate(int n) {
  Image image(n, n, 1);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const double dx = x + 0.5 - n / 2.0;
      const double dy = y + 0.5 - n / 2.0;
      image.pixel(x, y)[0] = static_cast<float>(0.5 + 0.5 * std::cos(std::numbers::pi * (dx * dx + dy * dy) / n));
    }
  }
  return image;
}

// The inverse map of a minification by s about the origin: output pixel centre q ↦ s·q.
std::vector<Point> minified_positions(int width, int height, double s, double angle = 0.0, Point shift = {}) {
  std::vector<Point> p;
  const Point rotation = std::polar(1.0, angle);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) p.push_back(s * rotation * Point(x + 0.5, y + 0.5) + shift);
  }
  return p;
}

// The source averaged exactly over output pixel (x, y)'s footprint under q ↦ s·q: its s×s block.
double box_average(const Image& source, int x, int y, int s) {
  double sum = 0.0;
  for (int j = 0; j < s; ++j) {
    for (int i = 0; i < s; ++i) sum += source.pixel(x * s + i, y * s + j)[0];
  }
  return sum / (s * s);
}

double alias_rms(const Image& out, const Image& source, int s) {
  double sum = 0.0;
  for (int y = 0; y < out.height; ++y) {
    for (int x = 0; x < out.width; ++x) {
      const double d = out.pixel(x, y)[0] - box_average(source, x, y, s);
      sum += d * d;
    }
  }
  return std::sqrt(sum / (out.width * out.height));
}

TEST(FootprintFilter, SimilarityMinificationsFollowTheExactFootprintAverage) {
  const Image plate = zone_plate(512);
  for (const int s : {2, 4, 8}) {
    const int n = 512 / s;
    const auto positions = minified_positions(n, n, s);
    ResampleStats stats;
    const Image footprint = resample_image(plate, positions, n, n,
                                           SamplingOptions{Interpolation::kBilinear, Border::kClamp}, {}, {}, &stats);
    const Image point = resample_image(
        plate, positions, n, n, SamplingOptions{Interpolation::kBilinear, Border::kClamp, SamplingFilter::kPoint});
    const double rms_footprint = alias_rms(footprint, plate, s);
    const double rms_point = alias_rms(point, plate, s);
    RecordProperty("alias_rms_footprint_" + std::to_string(s), std::to_string(rms_footprint));
    RecordProperty("alias_rms_point_" + std::to_string(s), std::to_string(rms_point));
    std::printf("minified %d×: alias RMS point %.4f, footprint %.4f (bicubic below)\n", s, rms_point, rms_footprint);
    // The point sample aliases (at 2× it lands on texel corners: bilinear there is the 2×2 box itself).
    if (s >= 4) {
      EXPECT_GT(rms_point, 0.12) << s;
    }
    EXPECT_LT(rms_footprint, 0.05) << s;
    EXPECT_EQ(stats.footprint_pixels, static_cast<std::size_t>(n * n));
    const Image cubic =
        resample_image(plate, positions, n, n, SamplingOptions{Interpolation::kBicubic, Border::kClamp});
    const double rms_cubic = alias_rms(cubic, plate, s);
    std::printf("minified %d× bicubic: alias RMS footprint %.4f\n", s, rms_cubic);
    EXPECT_LT(rms_cubic, 0.05) << s;
  }
}

TEST(FootprintFilter, RotatedMinificationAveragesLikeTheUnrotatedOne) {
  // A constant-frequency grating along x, minified 4× and turned 30°: the output must be the grating's mean (its
  // period of 2.5 px is far below what a 4× minification can hold), whatever the angle.
  Image grating(400, 400, 1);
  for (int y = 0; y < 400; ++y) {
    for (int x = 0; x < 400; ++x)
      grating.pixel(x, y)[0] = static_cast<float>(0.5 + 0.5 * std::cos(2.0 * std::numbers::pi * (x + 0.5) / 2.5));
  }
  const auto positions = minified_positions(40, 40, 4.0, std::numbers::pi / 6, Point(180, 20));
  const Image out =
      resample_image(grating, positions, 40, 40, SamplingOptions{Interpolation::kBilinear, Border::kClamp});
  const Image point = resample_image(grating, positions, 40, 40,
                                     SamplingOptions{Interpolation::kBilinear, Border::kClamp, SamplingFilter::kPoint});
  double worst = 0.0;
  double worst_point = 0.0;
  for (int y = 2; y < 38; ++y) {
    for (int x = 2; x < 38; ++x) {
      worst = std::max(worst, std::abs(out.pixel(x, y)[0] - 0.5));
      worst_point = std::max(worst_point, std::abs(point.pixel(x, y)[0] - 0.5));
    }
  }
  EXPECT_LT(worst, 0.03);
  EXPECT_GT(worst_point, 0.2);
}

TEST(FootprintFilter, WhereTheMapDoesNotMinifyTheReconstructionIsUnchanged) {
  Image source(64, 48, 3);
  for (std::size_t i = 0; i < source.pixels.size(); ++i)
    source.pixels[i] = static_cast<float>((i * 7919) % 256) / 255.0f;
  for (const Interpolation interpolation : {Interpolation::kBilinear, Interpolation::kBicubic}) {
    for (const double s : {1.0, 0.5, 0.37}) {
      for (const double angle : {0.0, 0.3}) {
        const auto positions = minified_positions(64, 48, s, angle, Point(7.3, 2.1));
        ResampleStats stats;
        const Image footprint =
            resample_image(source, positions, 64, 48, SamplingOptions{interpolation, Border::kRepeat}, {}, {}, &stats);
        const Image point = resample_image(source, positions, 64, 48,
                                           SamplingOptions{interpolation, Border::kRepeat, SamplingFilter::kPoint});
        EXPECT_EQ(footprint.pixels, point.pixels) << s << " " << angle;
        EXPECT_EQ(stats.footprint_pixels, 0u);
        EXPECT_EQ(stats.pyramid_levels, 0);
      }
    }
  }
}

TEST(FootprintFilter, FootprintAxesAreTheJacobiansSingularValues) {
  // K = R(40°)·diag(5, 2)·R(−15°): axes 5 and 2, the major along R(40°)·x.
  const Point r40 = std::polar(1.0, 40.0 * std::numbers::pi / 180);
  const Point r15 = std::polar(1.0, -15.0 * std::numbers::pi / 180);
  // K applied to the unit vectors: K·e = R40·diag(5,2)·(R15·e).
  const auto apply = [&](Point e) {
    const Point v = r15 * e;
    return r40 * Point(5 * v.real(), 2 * v.imag());
  };
  PixelJacobian j;
  j.dx = apply(Point(1, 0));
  j.dy = apply(Point(0, 1));
  const FootprintAxes axes = footprint_axes(j);
  EXPECT_NEAR(axes.major, 5.0, 1e-12);
  EXPECT_NEAR(axes.minor, 2.0, 1e-12);
  // The major axis along R(40°)·x, up to sign.
  EXPECT_NEAR(std::abs(std::sin(std::arg(axes.major_direction * std::conj(r40)))), 0.0, 1e-9);
}

TEST(FootprintFilter, GridJacobianIsExactForAffineMapsAndOneSidedAtTheEdges) {
  const auto positions = minified_positions(9, 5, 3.0, 0.25, Point(1, 2));
  const Point expected_dx = 3.0 * std::polar(1.0, 0.25);
  const Point expected_dy = 3.0 * std::polar(1.0, 0.25) * Point(0, 1);
  for (const auto& [x, y] : {std::pair{0, 0}, std::pair{4, 2}, std::pair{8, 4}}) {
    const PixelJacobian j = grid_jacobian(positions, 9, 5, x, y);
    EXPECT_LT(std::abs(j.dx - expected_dx), 1e-12);
    EXPECT_LT(std::abs(j.dy - expected_dy), 1e-12);
  }
}

TEST(FootprintFilter, PyramidLevelsFollowTheMinorAxisContinuously) {
  int level = 0;
  double next = 0.0;
  FootprintSampler::choose_level(1.5, 8, level, next);
  EXPECT_EQ(level, 0);
  EXPECT_EQ(next, 0.0);
  FootprintSampler::choose_level(4.0, 8, level, next);  // log2(4 / 2) = 1
  EXPECT_EQ(level, 1);
  EXPECT_NEAR(next, 0.0, 1e-12);
  FootprintSampler::choose_level(4.0 * std::sqrt(2.0), 8, level, next);
  EXPECT_EQ(level, 1);
  EXPECT_NEAR(next, 0.5, 1e-12);
  FootprintSampler::choose_level(1000.0, 3, level, next);  // beyond the pyramid: its last level
  EXPECT_EQ(level, 3);
  EXPECT_EQ(next, 0.0);
  // The filtered value is continuous across a level change: minifications by 7.99 and 8.01 of a smooth image.
  Image ramp(512, 512, 1);
  for (int y = 0; y < 512; ++y) {
    for (int x = 0; x < 512; ++x) ramp.pixel(x, y)[0] = static_cast<float>(std::sin(x / 40.0) * std::cos(y / 33.0));
  }
  const auto a = resample_image(ramp, minified_positions(16, 16, 3.99), 16, 16,
                                SamplingOptions{Interpolation::kBilinear, Border::kClamp});
  const auto b = resample_image(ramp, minified_positions(16, 16, 4.01), 16, 16,
                                SamplingOptions{Interpolation::kBilinear, Border::kClamp});
  for (int y = 2; y < 14; ++y) {
    for (int x = 2; x < 14; ++x) EXPECT_NEAR(a.pixel(x, y)[0], b.pixel(x, y)[0], 0.02) << x << "," << y;
  }
}

TEST(FootprintFilter, AWarpThatCrushesTheTextureAveragesAllOfItInAFewTaps) {
  // Every output pixel's footprint 10⁵ px wide (and 16:1 at 30°): the pyramid's last level, the texture's mean.
  Image source(64, 48, 1);
  double mean = 0.0;
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) {
      source.pixel(x, y)[0] = static_cast<float>((x * 7 + y * 13) % 17) / 16.0f;
      mean += source.pixel(x, y)[0];
    }
  }
  mean /= 64 * 48;
  std::vector<Point> positions;
  const Point axis = std::polar(1.0, 0.5);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) positions.push_back(axis * Point(1.6e6 * (x + 0.5), 1e5 * (y + 0.5)));
  }
  ResampleStats stats;
  const Image out = resample_image(source, positions, 8, 8, SamplingOptions{Interpolation::kBicubic, Border::kRepeat},
                                   {}, {}, &stats);
  EXPECT_EQ(stats.pyramid_levels, 6);  // down to 1×1
  for (const float v : out.pixels) EXPECT_NEAR(v, mean, 0.02);
}

TEST(FootprintFilter, PyramidCostsAtMostAThirdOfTheSource) {
  const Image plate = zone_plate(256);
  const auto positions = minified_positions(8, 8, 32.0);
  ResampleStats stats;
  resample_image(plate, positions, 8, 8, SamplingOptions{Interpolation::kBilinear, Border::kClamp}, {}, {}, &stats);
  EXPECT_GE(stats.pyramid_levels, 4);
  EXPECT_LE(stats.pyramid_bytes, plate.pixels.size() * sizeof(float) / 3);
}

}  // namespace
}  // namespace texwarp
