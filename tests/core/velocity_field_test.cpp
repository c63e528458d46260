// Tests of the vector field v(p, t) against a direct transcription of Eq. 2–7 (ordered pairs, gradient
// features, normalised weights), and of its finite, exact behaviour at and near features.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "random_features.hpp"
#include "texwarp/core/velocity_field.hpp"

namespace texwarp {
namespace {

// Eq. 7 written out term by term, with the paper's local frames (Eq. 2–3) instead of the complex closed form:
// x, y coordinates of p in the frame (F_i, F_j − F_i, R90(F_j − F_i)), the same coordinates applied to the
// velocities. Distances in units of the problem's weight length.
Point naive_field(const WarpProblem& problem, Point p, double t) {
  const double alpha = problem.alpha();
  const double unit = problem.weight_length_px();
  double wx = 0.0;
  double wy = 0.0;
  double wsum = 0.0;
  const auto& pos = problem.positional();
  for (std::size_t i = 0; i < pos.size(); ++i) {
    for (std::size_t j = 0; j < pos.size(); ++j) {
      if (i == j) continue;
      const double fix = pos[i].start.real() + t * pos[i].velocity.real();
      const double fiy = pos[i].start.imag() + t * pos[i].velocity.imag();
      const double ex = pos[j].start.real() + t * pos[j].velocity.real() - fix;  // F_j − F_i
      const double ey = pos[j].start.imag() + t * pos[j].velocity.imag() - fiy;
      // R90(e) so that (e, R90 e) has the orientation of (x, y): R90 (ex, ey) = (−ey, ex) here.
      const double nx = -ey;
      const double ny = ex;
      const double det = ex * ny - ey * nx;
      const double px = p.real() - fix;
      const double py = p.imag() - fiy;
      const double lx = (px * ny - py * nx) / det;  // p = F_i + lx·e + ly·n
      const double ly = (ex * py - ey * px) / det;
      const double dex = pos[j].velocity.real() - pos[i].velocity.real();
      const double dey = pos[j].velocity.imag() - pos[i].velocity.imag();
      const double vx = pos[i].velocity.real() + lx * dex + ly * (-dey);
      const double vy = pos[i].velocity.imag() + lx * dey + ly * dex;
      const double di = std::hypot(px, py) / unit;
      const double dj = std::hypot(p.real() - fix - ex, p.imag() - fiy - ey) / unit;
      const double w = std::pow(di, -alpha) * std::pow(dj, -alpha);
      wx += w * vx;
      wy += w * vy;
      wsum += w;
    }
  }
  for (const auto& g : problem.gradient()) {
    // Eq. 4: d/dt of M(t)·(local coords): translation velocity plus (ln S + iφ)·(p − F).
    const Point f = g.start + t * g.velocity;
    const Point v = g.velocity + g.rate * (p - f);
    const double w = std::pow(std::abs(p - f) / unit, -alpha);
    wx += w * v.real();
    wy += w * v.imag();
    wsum += w;
  }
  return {wx / wsum, wy / wsum};
}

TEST(VelocityField, MatchesTheDirectTranscriptionOfEquation7) {
  for (const double alpha : {1.0, 1.5, 2.0, 3.0, 4.5}) {
    WarpOptions options;
    options.alpha = alpha;
    testing::RandomFeatureSpec spec;
    spec.count = 12;
    spec.gradient_count = 3;
    spec.seed = static_cast<std::uint32_t>(alpha * 10);
    const WarpProblem problem(testing::random_features(spec, options), options);
    const VelocityField field(problem);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-50.0, 560.0);
    for (int k = 0; k < 200; ++k) {
      const Point p(u(rng), u(rng));
      const double t = (k % 11) / 10.0;
      const Point expected = naive_field(problem, p, t);
      const Point got = field(p, t);
      ASSERT_LE(std::abs(got - expected), 1e-9 * (1.0 + std::abs(expected))) << "alpha " << alpha << " k " << k;
    }
  }
}

TEST(VelocityField, IsExactlyTheFeatureVelocityAtAFeature) {
  WarpOptions options;
  testing::RandomFeatureSpec spec;
  spec.count = 9;
  spec.gradient_count = 2;
  const WarpProblem problem(testing::random_features(spec, options), options);
  const VelocityField field(problem);
  for (const double t : {0.0, 0.3, 1.0}) {
    for (const auto& f : problem.positional()) EXPECT_EQ(field(f.start + t * f.velocity, t), f.velocity);
    for (const auto& g : problem.gradient()) EXPECT_EQ(field(g.start + t * g.velocity, t), g.velocity);
  }
}

TEST(VelocityField, IsFiniteAndContinuousArbitrarilyNearAFeature) {
  WarpOptions options;
  testing::RandomFeatureSpec spec;
  spec.count = 7;
  spec.gradient_count = 1;
  const WarpProblem problem(testing::random_features(spec, options), options);
  const VelocityField field(problem);
  const double t = 0.4;
  for (const auto& f : problem.positional()) {
    const Point at = f.start + t * f.velocity;
    for (const double eps : {1e-3, 1e-6, 1e-9, 1e-12, 1e-15, 1e-150, 1e-300}) {
      const Point v = field(at + Point(eps, -0.5 * eps), t);
      ASSERT_TRUE(std::isfinite(v.real()) && std::isfinite(v.imag())) << eps;
      // |v − D| = O(eps·|∇v|); ∇v is bounded by the pair rates, well below 10 here.
      EXPECT_LE(std::abs(v - f.velocity), 10.0 * eps + 1e-12) << eps;
    }
  }
  const auto& g = problem.gradient()[0];
  const Point at = g.start + t * g.velocity;
  for (const double eps : {1e-6, 1e-12, 1e-300}) {
    const Point v = field(at + eps, t);
    ASSERT_TRUE(std::isfinite(v.real()) && std::isfinite(v.imag()));
    EXPECT_LE(std::abs(v - g.velocity), 10.0 * eps + 1e-12);
  }
}

TEST(VelocityField, WorkedExampleOfSection233TwoPairsDecideAtAFeature) {
  // Three positional features, p close to F1: the field tends to the weighted mean of v_12 and v_13 with
  // weights d3^α : d2^α (paper, Section 2.3.3), and v_12(F1) = v_13(F1) = D1. Check the weights one step
  // away from the limit: at p = F1 + ε the field's first-order term is the blend of the two pair rates.
  std::vector<Feature> features = {{"1", {100, 100}, {110, 100}},
                                   {"2", {300, 120}, {300, 150}},
                                   {"3", {150, 400}, {140, 390}}};
  WarpOptions options;
  options.prealign = Prealign::kNone;
  const WarpProblem problem(features, options);
  const VelocityField field(problem);
  const double eps = 1e-5;
  const Point p = Point(100, 100) + eps;
  const Point v = field(p, 0.0);
  const Point d1(10, 0), d2(0, 30), d3(-10, -10);
  const Point c12 = (d2 - d1) / (Point(300, 120) - Point(100, 100));
  const Point c13 = (d3 - d1) / (Point(150, 400) - Point(100, 100));
  const double r2 = std::abs(Point(300, 120) - Point(100, 100));
  const double r3 = std::abs(Point(150, 400) - Point(100, 100));
  const double w12 = r3 * r3 / (r2 * r2 + r3 * r3);  // d3^α / (d2^α + d3^α), α = 2
  const double w13 = r2 * r2 / (r2 * r2 + r3 * r3);
  const Point expected = d1 + eps * (w12 * c12 + w13 * c13);
  EXPECT_LE(std::abs(v - expected), 1e-9);
}

}  // namespace
}  // namespace texwarp
