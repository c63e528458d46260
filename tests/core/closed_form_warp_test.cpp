// The closed form of trivial warps (closed_form_warp.hpp): no features and pure similarities map every pixel by
// S⁻¹, computed here by hand and compared with per-pixel pathlines of a field that is almost zero.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "texwarp/core/closed_form_warp.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_warp.hpp"

namespace texwarp {
namespace {

constexpr int kWidth = 40;
constexpr int kHeight = 24;

// Three features moved by z ↦ 2·z + (6 − 4i): an exact similarity (powers of two, integer coordinates).
std::vector<Feature> doubled(double nudge_px = 0.0) {
  std::vector<Feature> f;
  for (const Point p : {Point(4, 4), Point(12, 6), Point(8, 14)}) f.push_back({"", p, 2.0 * p + Point(6, -4)});
  f[1].target += Point(nudge_px, 0.0);
  return f;
}

TEST(ClosedFormWarp, NoFeaturesIsTheIdentityAtEveryPixel) {
  const WarpProblem problem({}, WarpOptions{});
  ASSERT_TRUE(has_closed_form(problem));
  const std::vector<Point> grid = closed_form_inverse_map_grid(problem, kWidth, kHeight);
  ASSERT_EQ(grid.size(), static_cast<std::size_t>(kWidth * kHeight));
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) EXPECT_EQ(grid[y * kWidth + x], Point(x + 0.5, y + 0.5)) << x << "," << y;
  }
  const WarpCertificate c = closed_form_certificate(problem, 0.05);
  EXPECT_TRUE(c.exact);
  EXPECT_EQ(c.max_error_px_estimated, 0.0);
  EXPECT_EQ(c.max_error_px_sampled, 0.0);
  EXPECT_EQ(c.pathlines, 0u);
  EXPECT_EQ(c.min_jacobian_det, 1.0);
  EXPECT_EQ(c.tolerance_px, 0.05);
}

TEST(ClosedFormWarp, PureSimilarityIsSInverseAndMatchesPathlinesOfANearlyZeroField) {
  const WarpProblem problem(doubled(), WarpOptions{});
  ASSERT_TRUE(has_closed_form(problem)) << "the fit of an exact similarity left a residual";
  const std::vector<Point> grid = closed_form_inverse_map_grid(problem, kWidth, kHeight);
  // S⁻¹(q) = (q − (6 − 4i)) / 2, by hand.
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const Point expected = (Point(x + 0.5, y + 0.5) - Point(6, -4)) / 2.0;
      EXPECT_LT(std::abs(grid[y * kWidth + x] - expected), 1e-12) << x << "," << y;
    }
  }
  EXPECT_NEAR(closed_form_certificate(problem, 0.05).min_jacobian_det, 0.25, 1e-12);

  // A target nudged by 1e-6 px makes the field non-zero: every pixel then gets its own pathline on the CPU
  // reference, and the two maps agree within the nudge's reach.
  const WarpProblem nudged(doubled(1e-6), WarpOptions{});
  ASSERT_FALSE(has_closed_form(nudged));
  CpuBackend cpu;
  const std::vector<Point> pathlines = cpu.inverse_map_grid(nudged, kWidth, kHeight, {});
  double worst = 0.0;
  for (std::size_t i = 0; i < grid.size(); ++i) worst = std::max(worst, std::abs(pathlines[i] - grid[i]));
  EXPECT_LT(worst, 1e-3);
}

TEST(ClosedFormWarp, WarpImageTakesItAndSaysSoInItsCertificate) {
  const WarpProblem problem(doubled(), WarpOptions{});
  Image source(16, 12, 1, -1);
  for (std::size_t i = 0; i < source.pixels.size(); ++i) source.pixels[i] = static_cast<float>(i % 7) / 7.0f;
  ImageWarpOptions options;
  options.width = kWidth;
  options.height = kHeight;
  options.border = Border::kClamp;
  for (const bool exact : {false, true}) {
    options.exact = exact;
    CpuBackend cpu;
    WarpCertificate certificate;
    const Image warped = warp_image(cpu, problem, source, options, {}, &certificate);
    EXPECT_TRUE(certificate.exact);
    EXPECT_EQ(certificate.pathlines, 0u);
    EXPECT_EQ(certificate.cells, 0u);
    const Image expected = resample_image(source, closed_form_inverse_map_grid(problem, kWidth, kHeight), kWidth,
                                          kHeight, SamplingOptions{options.interpolation, options.border});
    EXPECT_EQ(warped.pixels, expected.pixels);
  }
}

// A closed form that moves pixel centres onto pixel centres (the identity, a translation by whole pixels) copies
// pixels instead of interpolating them: bit for bit what sampling at S⁻¹ gives, inside the source and outside it,
// for both interpolations, every border, with and without alpha, including −0 (the sampler's sum makes it +0).
TEST(ClosedFormWarp, AWholePixelTranslationCopiesExactlyWhatSamplingGives) {
  const WarpProblem identity({}, WarpOptions{});
  const WarpProblem moved({{"", Point(5, 7), Point(8, 5)}}, WarpOptions{});  // one feature: translation (3, −2)
  ASSERT_TRUE(has_closed_form(moved));
  ASSERT_EQ(moved.prealignment().inverse().a, Point(1, 0));
  ASSERT_EQ(moved.prealignment().inverse().b, Point(-3, 2));
  for (const int channels : {3, 4}) {
    Image source(17, 11, channels, channels == 4 ? 3 : -1);
    for (std::size_t i = 0; i < source.pixels.size(); ++i) {
      source.pixels[i] = static_cast<float>((i * 37) % 101) / 100.0f - 0.1f;
    }
    source.pixels[5] = -0.0f;
    for (const WarpProblem* problem : {&identity, &moved}) {
      for (const Interpolation interpolation : {Interpolation::kBilinear, Interpolation::kBicubic}) {
        for (const Border border : {Border::kTransparent, Border::kClamp, Border::kRepeat}) {
          for (const auto& [w, h] : {std::pair{17, 11}, std::pair{23, 9}}) {
            ImageWarpOptions options;
            options.width = w;
            options.height = h;
            options.interpolation = interpolation;
            options.border = border;
            CpuBackend cpu;
            WarpCertificate certificate;
            const Image warped = warp_image(cpu, *problem, source, options, {}, &certificate);
            EXPECT_TRUE(certificate.exact);
            const Image expected = resample_image(source, closed_form_inverse_map_grid(*problem, w, h), w, h,
                                                  SamplingOptions{interpolation, border});
            ASSERT_EQ(warped.channels, expected.channels);
            EXPECT_EQ(warped.alpha_channel, expected.alpha_channel);
            ASSERT_EQ(warped.pixels.size(), expected.pixels.size());
            EXPECT_EQ(std::memcmp(warped.pixels.data(), expected.pixels.data(), expected.pixels.size() * 4), 0)
                << channels << " channels, " << (problem == &identity ? "identity" : "translation") << ", "
                << static_cast<int>(interpolation) << ", " << static_cast<int>(border) << ", " << w << "×" << h;
          }
        }
      }
    }
  }
}

TEST(ClosedFormWarp, RefusesAFieldThatIsNotZero) {
  const WarpProblem nudged(doubled(0.5), WarpOptions{});
  EXPECT_THROW(closed_form_inverse_map_grid(nudged, 4, 4), std::logic_error);
}

}  // namespace
}  // namespace texwarp
