// Tests of the least-squares similarity (pre-alignment) against Eigen's independent Umeyama implementation.
#include <gtest/gtest.h>

#include <random>

#include <Eigen/Geometry>

#include "texwarp/core/similarity.hpp"

namespace texwarp {
namespace {

TEST(Similarity, RecoversAnExactSimilarity) {
  const Similarity truth{std::polar(1.7, 0.6), {12.0, -30.0}};
  std::vector<Point> src = {{0, 0}, {100, 10}, {40, 80}, {-20, 55}};
  std::vector<Point> dst;
  dst.reserve(src.size());
  for (Point p : src) dst.push_back(truth(p));
  const Similarity fit = fit_similarity(src, dst);
  EXPECT_NEAR(std::abs(fit.a - truth.a), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(fit.b - truth.b), 0.0, 1e-10);
}

TEST(Similarity, MatchesEigenUmeyamaOnNoisyPoints) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-200.0, 200.0);
  std::normal_distribution<double> noise(0.0, 8.0);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 3 + trial;
    std::vector<Point> src;
    std::vector<Point> dst;
    Eigen::Matrix2Xd a(2, n);
    Eigen::Matrix2Xd b(2, n);
    const Point rot = std::polar(0.5 + 0.1 * trial, 0.3 * trial);
    for (int k = 0; k < n; ++k) {
      const Point p(u(rng), u(rng));
      const Point q = rot * p + Point(5.0, -3.0) + Point(noise(rng), noise(rng));
      src.push_back(p);
      dst.push_back(q);
      a.col(k) << p.real(), p.imag();
      b.col(k) << q.real(), q.imag();
    }
    const Eigen::Matrix3d t = Eigen::umeyama(a, b, true);
    const Similarity fit = fit_similarity(src, dst);
    // Eigen's c·R as a complex number: first column (c·cos, c·sin).
    EXPECT_NEAR(fit.a.real(), t(0, 0), 1e-9) << trial;
    EXPECT_NEAR(fit.a.imag(), t(1, 0), 1e-9) << trial;
    EXPECT_NEAR(fit.b.real(), t(0, 2), 1e-7) << trial;
    EXPECT_NEAR(fit.b.imag(), t(1, 2), 1e-7) << trial;
  }
}

TEST(Similarity, DegenerateSets) {
  EXPECT_EQ(fit_similarity({}, {}).a, Point(1.0, 0.0));
  const Similarity one = fit_similarity({{3, 4}}, {{10, 1}});
  EXPECT_EQ(one.a, Point(1.0, 0.0));
  EXPECT_EQ(one({3, 4}), Point(10, 1));
  const Similarity same = fit_similarity({{1, 2}, {5, 9}}, {{1, 2}, {5, 9}});
  EXPECT_EQ(same.a, Point(1.0, 0.0));
  EXPECT_EQ(same.b, Point(0.0, 0.0));
}

TEST(Similarity, InverseUndoes) {
  const Similarity s{std::polar(2.5, -1.0), {7.0, 8.0}};
  const Point p(13.0, -4.0);
  EXPECT_NEAR(std::abs(s.inverse()(s(p)) - p), 0.0, 1e-12);
}

}  // namespace
}  // namespace texwarp
