// Mirrored feature sets (core/mirror.hpp): the two least-squares fits against a direct 4-parameter solve, how
// rarely sets that are no mirror image are flagged, the mirrored features' warp (a similarity, exact at the
// features), and the image flip pixel by pixel.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/mirror.hpp"
#include "texwarp/core/warp_backend.hpp"
#include "texwarp/core/warp_problem.hpp"

namespace texwarp {
namespace {

// Σ|M·P + t − Q|² minimised over M = [[a, −b], [b, a]] (proper) or [[a, b], [b, −a]] (reflected), by least squares.
double direct_residual(const std::vector<Feature>& f, bool reflected) {
  const int n = static_cast<int>(f.size());
  Eigen::MatrixXd a(2 * n, 4);
  Eigen::VectorXd q(2 * n);
  for (int i = 0; i < n; ++i) {
    const double x = f[i].source.real(), y = f[i].source.imag();
    const double s = reflected ? -1.0 : 1.0;
    const Eigen::Index r = Eigen::Index{2} * i;
    a.row(r) << x, (reflected ? y : -y), 1.0, 0.0;
    a.row(r + 1) << s * y, x, 0.0, 1.0;
    q(r) = f[i].target.real();
    q(r + 1) = f[i].target.imag();
  }
  const Eigen::VectorXd p = a.colPivHouseholderQr().solve(q);
  return (a * p - q).squaredNorm();
}

std::vector<Feature> random_sources(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(20.0, 236.0);
  std::vector<Feature> f(static_cast<std::size_t>(n));
  for (Feature& x : f) x.source = Point(u(rng), u(rng));
  return f;
}

TEST(Mirror, FitsAgreeWithADirectLeastSquaresSolve) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.5);
  std::uniform_real_distribution<double> u(20.0, 236.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Feature> f = random_sources(6, rng);
    const Point a = std::polar(0.8 + 0.05 * trial, 0.3 * trial);
    for (Feature& x : f) x.target = (trial % 2 ? a * std::conj(x.source) : Point(u(rng), u(rng))) + Point(40, 9);
    for (Feature& x : f) x.target += Point(noise(rng), noise(rng));
    const MirrorFit fit = fit_mirror(f);
    EXPECT_NEAR(fit.proper_residual, direct_residual(f, false), 1e-6 * (1 + fit.proper_residual));
    EXPECT_NEAR(fit.reflected_residual, direct_residual(f, true), 1e-6 * (1 + fit.reflected_residual));
    EXPECT_EQ(fit.mirrored, trial % 2 == 1) << "trial " << trial << " ratio " << fit.residual_ratio;
  }
}

TEST(Mirror, FewerThanThreeFeaturesAreNeverMirrored) {
  std::vector<Feature> f(2);
  f[0].source = Point(0, 0);
  f[1].source = Point(10, 0);
  f[0].target = Point(10, 0);
  f[1].target = Point(0, 0);
  EXPECT_FALSE(fit_mirror(f).mirrored);
  EXPECT_EQ(fit_mirror(f).residual_ratio, 1.0);
}

// How often a set whose targets are unrelated to its sources falls below the threshold (printed: the figure that
// justifies kMirrorResidualRatio), and how often a mirrored set with 2 px noise does.
TEST(Mirror, TheThresholdSeparatesMirroredFromUnrelatedSets) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(20.0, 236.0);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (int n : {3, 5, 10, 50}) {
    int unrelated_flagged = 0, mirrored_flagged = 0;
    constexpr int kSets = 2000;
    for (int s = 0; s < kSets; ++s) {
      std::vector<Feature> f = random_sources(n, rng);
      for (Feature& x : f) x.target = Point(u(rng), u(rng));
      unrelated_flagged += fit_mirror(f).mirrored ? 1 : 0;
      const Point a = std::polar(1.0, 2.0 * std::numbers::pi * s / kSets);
      for (Feature& x : f)
        x.target = a * Point(256.0 - x.source.real(), x.source.imag()) + Point(noise(rng), noise(rng));
      mirrored_flagged += fit_mirror(f).mirrored ? 1 : 0;
    }
    std::printf("n = %d: unrelated sets flagged %.2f%%, mirrored sets (2 px noise) flagged %.2f%%\n", n,
                100.0 * unrelated_flagged / kSets, 100.0 * mirrored_flagged / kSets);
    // Three points are the weak case (a triangle and its mirror image differ only in their shape's handedness).
    EXPECT_LT(unrelated_flagged, n == 3 ? kSets * 6 / 100 : kSets / 100) << n;
    EXPECT_GT(mirrored_flagged, n == 3 ? kSets * 90 / 100 : kSets * 99 / 100) << n;
  }
}

TEST(Mirror, TheMirroredSetWarpsAsASimilarityExactAtItsFeatures) {
  // Targets: the sources mirrored about x = 128, rotated 20° and scaled 1.1 about the centre, plus a gradient
  // feature whose target frame is the mirror of its source frame carried by that similarity.
  constexpr double kWidth = 256.0;
  std::mt19937 rng(3);
  std::vector<Feature> f = random_sources(8, rng);
  const Point a = std::polar(1.1, 20.0 * std::numbers::pi / 180.0);
  const Point centre(128.0, 128.0);
  const auto similarity = [&](Point p) { return centre + a * (p - centre); };
  for (Feature& x : f) x.target = similarity(Point(kWidth - x.source.real(), x.source.imag()));
  f[0].source_frame = Frame{0.4, 1.0};
  f[0].target_frame = Frame{std::numbers::pi - 0.4 + std::arg(a), 1.1};
  EXPECT_TRUE(fit_mirror(f).mirrored);
  const proto::MirrorReport found = mirror_report(f, false);
  EXPECT_TRUE(found.detected);
  EXPECT_EQ(found.suggestion, std::string(kMirrorSuggestion));
  EXPECT_FALSE(mirror_report(f, true).suggestion);
  EXPECT_FALSE(mirror_report(mirror_features(f, kWidth), false).detected);
  const std::vector<Feature> mirrored = mirror_features(f, kWidth);
  EXPECT_FALSE(fit_mirror(mirrored).mirrored);
  EXPECT_LT(fit_mirror(mirrored).proper_residual, 1e-18 * 1e6);
  EXPECT_NEAR(mirrored[0].source_frame->angle_rad, std::numbers::pi - 0.4, 1e-15);
  for (std::size_t i = 0; i < f.size(); ++i) {
    EXPECT_EQ(mirrored[i].source, Point(kWidth - f[i].source.real(), f[i].source.imag()));
    EXPECT_EQ(mirrored[i].target, f[i].target);
  }
  const WarpProblem problem(mirrored, WarpOptions{});
  CpuBackend backend;
  std::vector<Point> sources;
  sources.reserve(mirrored.size());
  for (const Feature& x : mirrored) sources.push_back(x.source);
  std::vector<Point> mapped = sources;
  map_points(backend, problem, mapped, Direction::kForward);
  for (std::size_t i = 0; i < mapped.size(); ++i) EXPECT_LT(std::abs(mapped[i] - mirrored[i].target), 1e-3) << i;
  // Low distortion: at random points the warp is the similarity itself (the pre-alignment fits it exactly).
  std::uniform_real_distribution<double> u(0.0, kWidth);
  std::vector<Point> probe(200);
  for (Point& p : probe) p = Point(u(rng), u(rng));
  std::vector<Point> image = probe;
  map_points(backend, problem, image, Direction::kForward);
  for (std::size_t i = 0; i < probe.size(); ++i) EXPECT_LT(std::abs(image[i] - similarity(probe[i])), 1e-3) << i;
}

TEST(Mirror, TheImageFlipMovesEveryPixelAcross) {
  Image image(5, 3, 2);
  for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = static_cast<float>(i);
  Image flipped = image;
  mirror_image(flipped);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      for (int c = 0; c < 2; ++c) EXPECT_EQ(flipped.pixel(x, y)[c], image.pixel(4 - x, y)[c]);
    }
  }
}

}  // namespace
}  // namespace texwarp
