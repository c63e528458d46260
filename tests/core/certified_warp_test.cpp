// Tests of the fast, certified path: the closed-form field gradient and the variational Jacobian against
// finite differences, the lattice map against per-pixel pathlines, the certificate, and the baselines.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>
#include <string>

#include "crossing_features.hpp"
#include "point_compare.hpp"
#include "random_features.hpp"
#include "reference_grid.hpp"
#include "texwarp/core/baseline_warp.hpp"
#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/hermite_cell.hpp"
#include "texwarp/core/jacobian_stats.hpp"
#include "texwarp/core/moving_least_squares.hpp"
#include "texwarp/core/numerical_error.hpp"
#include "texwarp/core/thin_plate_spline.hpp"

namespace texwarp {
namespace {

WarpProblem random_problem(int count, int gradient, std::uint32_t seed, double alpha = 2.0, double tolerance = 0.01) {
  WarpOptions o;
  o.alpha = alpha;
  o.tolerance_px = tolerance;
  WarpOptions generation = o;
  generation.min_separation_px = 10.0;
  testing::RandomFeatureSpec spec;
  spec.count = count;
  spec.gradient_count = gradient;
  spec.width = 160;
  spec.height = 120;
  spec.margin = 8;
  spec.max_displacement = 15;
  spec.seed = seed;
  return WarpProblem(testing::random_features(spec, generation), o);
}

TEST(FieldGradient, MatchesFiniteDifferencesOfTheField) {
  for (const double alpha : {1.5, 2.0, 3.0}) {
    const WarpProblem problem = random_problem(12, 3, 4, alpha);
    const VelocityField field(problem);
    std::mt19937 rng(8);
    std::uniform_real_distribution<double> u(-20.0, 180.0);
    for (int k = 0; k < 200; ++k) {
      FieldCoefficients c;
      field.coefficients(k / 200.0, c);
      Point p(u(rng), u(rng));
      if (k % 4 == 0) p = c.positions[k % c.positions.size()] + Point(0.3, -0.2);  // near a feature
      FieldGradient g;
      const Point v = field.evaluate(c, p, g);
      EXPECT_EQ(v, field.evaluate(c, p));
      const double h = 1e-5;
      const Point fx = (field.evaluate(c, p + h) - field.evaluate(c, p - h)) / (2 * h);
      const Point fy = (field.evaluate(c, p + Point(0, h)) - field.evaluate(c, p - Point(0, h))) / (2 * h);
      const double scale = 1e-3 + std::abs(g.dx) + std::abs(g.dy);
      ASSERT_LE(std::abs(fx - g.dx) / scale, 1e-5) << alpha << " " << k;
      ASSERT_LE(std::abs(fy - g.dy) / scale, 1e-5) << alpha << " " << k;
    }
  }
}

TEST(FieldGradient, AtAGradientFeatureIsItsRate) {
  const WarpProblem problem = random_problem(8, 3, 5);
  const VelocityField field(problem);
  FieldCoefficients c;
  field.coefficients(0.5, c);
  for (std::size_t g = 0; g < c.grad_positions.size(); ++g) {
    FieldGradient grad;
    field.evaluate(c, c.grad_positions[g], grad);
    EXPECT_LE(std::abs(grad.dx - c.grad_c[g]), 1e-12);
    EXPECT_LE(std::abs(grad.dy - Point(0, 1) * c.grad_c[g]), 1e-12);
  }
}

TEST(VariationalJacobian, MatchesFiniteDifferencesOfTheMap) {
  const WarpProblem problem = random_problem(15, 3, 6, 2.0, 1e-9);
  CpuBackend cpu;
  std::vector<Point> pts;
  pts.reserve(40);
  for (int k = 0; k < 40; ++k) pts.emplace_back(5.0 + 3.7 * k, 110.0 - 2.3 * k);
  for (const Direction d : {Direction::kForward, Direction::kInverse}) {
    std::vector<Point> mapped = pts;
    std::vector<FlowJacobian> jac(pts.size());
    map_points_with_jacobian(cpu, problem, mapped, jac, d);
    std::vector<Point> plain = pts;
    map_points(cpu, problem, plain, d);
    const double h = 1e-4;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      EXPECT_LE(std::abs(mapped[i] - plain[i]), 1e-7);
      std::vector<Point> probe = {pts[i] + h, pts[i] - h, pts[i] + Point(0, h), pts[i] - Point(0, h)};
      map_points(cpu, problem, probe, d);
      const Point dx = (probe[0] - probe[1]) / (2 * h);
      const Point dy = (probe[2] - probe[3]) / (2 * h);
      EXPECT_LE(std::abs(dx - jac[i].dx), 1e-5 * (1 + std::abs(dx))) << i;
      EXPECT_LE(std::abs(dy - jac[i].dy), 1e-5 * (1 + std::abs(dy))) << i;
    }
  }
}

// f(x, y) = (x³ − y + x²y², 2xy + y² + xy²) in complex form, its Jacobian and its twist ∂²f/∂x∂y = (4xy, 2 + 2y):
// bicubic, with a twist that varies across a cell and is at most quadratic along each edge.
Point bicubic(Point p) {
  const double x = p.real();
  const double y = p.imag();
  return Point(x * x * x - y + x * x * y * y, 2 * x * y + y * y + x * y * y);
}
FlowJacobian bicubic_jacobian(Point p) {
  const double x = p.real();
  const double y = p.imag();
  return FlowJacobian{Point(3 * x * x + 2 * x * y * y, 2 * y + y * y),
                      Point(-1.0 + 2 * x * x * y, 2 * x + 2 * y + 2 * x * y)};
}

// The cell, of `size` px from `corner`, is the bicubic itself: values and Jacobians across it to 1e-9.
void expect_reproduces_bicubic(const HermiteCell& cell, Point corner, double size) {
  for (const double u : {0.0, 0.25, 0.5, 0.9}) {
    for (const double v : {0.0, 0.3, 1.0}) {
      const Point p = corner + Point(u * size, v * size);
      FlowJacobian j;
      EXPECT_LE(std::abs(cell.value(u, v, j) - bicubic(p)), 1e-9 * std::abs(bicubic(p)));
      EXPECT_LE(std::abs(j.dx - bicubic_jacobian(p).dx), 1e-9 * std::abs(bicubic_jacobian(p).dx));
      EXPECT_LE(std::abs(j.dy - bicubic_jacobian(p).dy), 1e-9 * std::abs(bicubic_jacobian(p).dy));
    }
  }
}

// With exact corner and midpoint Jacobians the interpolant is the bicubic itself.
TEST(HermiteCell, ReproducesBicubicsWithTheirDerivatives) {
  const double size = 4.0;
  const Point corners[4] = {{1, 2}, {5, 2}, {1, 6}, {5, 6}};
  Point values[4];
  FlowJacobian jacobians[4];
  for (int c = 0; c < 4; ++c) {
    values[c] = bicubic(corners[c]);
    jacobians[c] = bicubic_jacobian(corners[c]);
  }
  const Point c0 = corners[0];
  const FlowJacobian midpoints[4] = {
      bicubic_jacobian(c0 + Point(size / 2, 0)), bicubic_jacobian(c0 + Point(0, size / 2)),
      bicubic_jacobian(c0 + Point(size, size / 2)), bicubic_jacobian(c0 + Point(size / 2, size))};
  expect_reproduces_bicubic(HermiteCell(values, jacobians, midpoints, size), c0, size);
}

// The same from its corners' values and Jacobians and its exact twists ∂²f/∂u∂v = size²·∂²f/∂x∂y: the interpolant
// the lattice's 8 px cells use, their twists estimated from neighbouring corners.
TEST(HermiteCell, ReproducesBicubicsFromGivenTwists) {
  const double size = 8.0;
  const Point corners[4] = {{-3, 2}, {5, 2}, {-3, 10}, {5, 10}};
  Point values[4], twists[4];
  FlowJacobian jacobians[4];
  for (int c = 0; c < 4; ++c) {
    const double x = corners[c].real(), y = corners[c].imag();
    values[c] = bicubic(corners[c]);
    jacobians[c] = bicubic_jacobian(corners[c]);
    twists[c] = size * size * Point(4 * x * y, 2 + 2 * y);
  }
  expect_reproduces_bicubic(HermiteCell::with_twists(values, jacobians, twists, size), corners[0], size);
}

struct LatticeCase {
  int count;
  int gradient;
  double alpha;
  double tolerance;
};

class CertifiedLattice : public ::testing::TestWithParam<LatticeCase> {};

TEST_P(CertifiedLattice, EveryPixelWithinToleranceOfItsPathline) {
  const LatticeCase c = GetParam();
  const WarpProblem problem = random_problem(c.count, c.gradient, static_cast<std::uint32_t>(c.count), c.alpha);
  CpuBackend cpu;
  const int w = 157;
  const int h = 119;
  CertifiedGridOptions options;
  options.tolerance_px = c.tolerance;
  WarpCertificate cert;
  const std::vector<Point> fast = certified_inverse_map_grid(cpu, problem, w, h, options, {}, cert);
  // The reference: a pathline per pixel at a much tighter tolerance.
  WarpOptions tight = problem.options();
  tight.tolerance_px = 1e-5;
  const std::vector<Point> exact = cpu.inverse_map_grid(WarpProblem(problem.features(), tight), w, h, {});
  double worst = 0.0;
  for (std::size_t i = 0; i < fast.size(); ++i) worst = std::max(worst, std::abs(fast[i] - exact[i]));
  EXPECT_LE(worst, c.tolerance);
  EXPECT_LE(cert.max_error_px_estimated, c.tolerance);
  EXPECT_LE(cert.max_error_px_sampled, c.tolerance);
  EXPECT_EQ(cert.sampled_pixels, 1024u);
  EXPECT_GT(cert.min_jacobian_det, 0.0);
  EXPECT_EQ(cert.nonpositive_jacobians, 0u);
  // Never more work than a pathline per pixel (plus the sample): dense sets fall back to the exact path.
  EXPECT_LE(cert.pathlines, static_cast<std::size_t>(w * h) + 1024u);
  if (c.count <= 12 && c.tolerance >= 0.05) {
    EXPECT_FALSE(cert.exact) << "the lattice should pay here";
  }
  if (!cert.exact) {
    // Only corners and edge midpoints carry Jacobians; the other check points and the sample are plain.
    EXPECT_GT(cert.jacobian_pathlines, 0u);
    EXPECT_LE(cert.jacobian_pathlines + cert.sampled_pixels, cert.pathlines);
  }
  // The lattice's determinants agree in sign with the exact map's everywhere it was sampled.
  std::vector<Point> centres;
  for (int y = 0; y < h; y += 7) {
    for (int x = 0; x < w; x += 7) centres.emplace_back(x + 0.5, y + 0.5);
  }
  const JacobianStats exact_stats =
      summarize_determinants(warp_jacobian_determinants(cpu, problem, centres, Direction::kInverse));
  EXPECT_EQ(exact_stats.nonpositive, 0u);
}

INSTANTIATE_TEST_SUITE_P(RandomSets, CertifiedLattice,
                         ::testing::Values(LatticeCase{2, 0, 2.0, 0.05}, LatticeCase{5, 2, 1.5, 0.05},
                                           LatticeCase{12, 3, 2.0, 0.05}, LatticeCase{25, 4, 3.0, 0.05},
                                           LatticeCase{12, 3, 2.0, 0.005}),
                         [](const ::testing::TestParamInfo<LatticeCase>& param_info) {
                           return std::to_string(param_info.param.count) + "_features_tol_" +
                                  std::to_string(static_cast<int>(param_info.param.tolerance * 1000)) + "e_3";
                         });

TEST(CertifiedLattice, SampledCheckOnALargerGridWithManyFeatures) {
  WarpOptions o;
  WarpOptions generation = o;
  generation.min_separation_px = 10.0;
  testing::RandomFeatureSpec spec;
  spec.count = 60;
  spec.gradient_count = 6;
  spec.max_displacement = 30;
  spec.seed = 77;
  const WarpProblem problem(testing::random_features(spec, generation), o);
  CpuBackend cpu;
  CertifiedGridOptions options;
  WarpCertificate cert;
  const auto fast = certified_inverse_map_grid(cpu, problem, 512, 512, options, {}, cert);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pick(0, 512 * 512 - 1);
  std::vector<std::size_t> idx;
  std::vector<Point> pts;
  for (int k = 0; k < 400; ++k) {
    idx.push_back(static_cast<std::size_t>(pick(rng)));
    const std::size_t column = idx.back() % 512;
    const std::size_t row = idx.back() / 512;
    pts.emplace_back(static_cast<double>(column) + 0.5, static_cast<double>(row) + 0.5);
  }
  WarpOptions tight = o;
  tight.tolerance_px = 1e-5;
  map_points(cpu, WarpProblem(problem.features(), tight), pts, Direction::kInverse);
  double worst = 0.0;
  for (std::size_t k = 0; k < pts.size(); ++k) worst = std::max(worst, std::abs(pts[k] - fast[idx[k]]));
  EXPECT_LE(worst, options.tolerance_px);
  std::cout << "pathlines " << cert.pathlines << " (Jacobian " << cert.jacobian_pathlines << ", per pixel "
            << cert.pixel_pathlines << "), cells " << cert.cells << "\n";
  EXPECT_LT(cert.pathlines, 512u * 512u / 4u);
}

TEST(CertifiedLattice, ExactCertificateCountsEveryPixel) {
  const WarpProblem problem = random_problem(6, 1, 9);
  CpuBackend cpu;
  CertifiedGridOptions options;
  options.samples = 100;
  const WarpCertificate c = exact_grid_certificate(cpu, problem, 40, 30, options, {});
  EXPECT_TRUE(c.exact);
  EXPECT_EQ(c.pathlines, 40u * 30u + 100u);
  EXPECT_EQ(c.jacobian_pathlines, 100u);
  EXPECT_EQ(c.max_error_px_sampled, 0.0);
  EXPECT_GT(c.min_jacobian_det, 0.0);
}

// A lattice asked for less than its problem's integration tolerance: whatever path it takes, every pixel stays
// within what was asked (its exact fallback integrates to the lattice's tolerance, not the problem's 0.01); and a
// lattice tolerance whose integration share would fall below the smallest tolerance a problem accepts is taken,
// not refused for a tolerance the caller never gave.
TEST(CertifiedLattice, ATighterToleranceThanTheProblemsIsMetAndTheSmallestIsAccepted) {
  const WarpProblem problem = random_problem(6, 1, 9);  // integration tolerance 0.01
  ASSERT_EQ(problem.tolerance_px(), 0.01);
  CpuBackend cpu;
  WarpOptions reference_options = problem.options();
  reference_options.tolerance_px = 1e-9;
  const WarpProblem reference(problem.features(), reference_options);
  const int w = 24, h = 18;
  std::vector<Point> truth;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) truth.emplace_back(x + 0.5, y + 0.5);
  }
  map_points(cpu, reference, truth, Direction::kInverse, {});
  for (const double tolerance : {2e-3, 3e-10}) {
    CertifiedGridOptions options;
    options.tolerance_px = tolerance;
    options.samples = 16;
    WarpCertificate cert;
    const std::vector<Point> grid = certified_inverse_map_grid(cpu, problem, w, h, options, {}, cert);
    EXPECT_LE(cert.max_error_px_bound, tolerance) << tolerance;
    double worst = 0.0;
    for (std::size_t i = 0; i < grid.size(); ++i) worst = std::max(worst, std::abs(grid[i] - truth[i]));
    // Against a reference at 1e-9, a tolerance of 3e-10 cannot be measured: there the map is held to 1e-8.
    EXPECT_LE(worst, std::max(tolerance, 1e-8)) << tolerance;
  }
}

// The certificate's bound against every pixel: warps of 128² outputs from several families (independent
// random displacements, a smooth displacement field, rigidly moved clusters, gradient features), each pixel
// measured against the CPU reference integrated at 1e-9; the bound must hold above the measured maximum, and
// for the lattice stay within the tolerance asked for. clustered 60 at 0.05: with the check points alone (no edge
// estimates) the lattice measured 0.058 px against a bound of 0.050 (issue 15).
struct BoundCase {
  const char* family;
  int count;
  double tolerance;
};

std::vector<Feature> bound_case_features(const BoundCase& c, const WarpOptions& o) {
  const double size = 128.0;
  std::mt19937 rng(static_cast<std::uint32_t>(c.count * 13 + 7));
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const std::string family = c.family;
  if (family == "independent" || family == "gradient") {
    WarpOptions generation = o;
    generation.min_separation_px = 4.0;
    testing::RandomFeatureSpec spec;
    spec.count = c.count;
    spec.gradient_count = family == "gradient" ? c.count / 3 : 0;
    spec.width = size;
    spec.height = size;
    spec.margin = 8;
    spec.max_displacement = 0.06 * size;
    spec.seed = static_cast<std::uint32_t>(c.count);
    return testing::random_features(spec, generation);
  }
  std::vector<Feature> f;
  if (family == "smooth") {  // a jittered grid displaced by two Gaussian bumps of width a quarter of the image
    const int side = static_cast<int>(std::ceil(std::sqrt(c.count)));
    for (int k = 0; k < c.count; ++k) {
      const int column = k % side;
      const int row = k / side;
      const Point p(12.0 + column * 104.0 / std::max(1, side - 1) + 2.0 * unit(rng),
                    12.0 + row * 104.0 / std::max(1, side - 1) + 2.0 * unit(rng));
      const Point d = Point(6.0, -4.0) * std::exp(-std::norm(p - Point(40, 50)) / (2 * 32.0 * 32.0)) +
                      Point(-5.0, 5.0) * std::exp(-std::norm(p - Point(90, 80)) / (2 * 32.0 * 32.0));
      f.push_back({"s" + std::to_string(k), p, p + d});
    }
    return f;
  }
  // clustered: three groups of radius 10 px, each shifted and turned rigidly
  const Point centres[3] = {{35, 40}, {90, 45}, {60, 95}};
  for (int k = 0; k < c.count; ++k) {
    const int g = k % 3;
    const Point offset = 10.0 * std::sqrt(0.5 + 0.5 * unit(rng)) * std::polar(1.0, M_PI * unit(rng));
    const Point turn = std::polar(1.0, 0.15 * (g - 1));
    const Point shift(5.0 * (g - 1), 4.0 * (1 - g));
    f.push_back({"c" + std::to_string(k), centres[g] + offset, centres[g] + shift + turn * offset});
  }
  return f;
}

class CertificateBound : public ::testing::TestWithParam<BoundCase> {};

TEST_P(CertificateBound, HoldsAboveEveryPixelsMeasuredError) {
  const BoundCase c = GetParam();
  WarpOptions o;
  const WarpProblem problem(bound_case_features(c, o), o);
  const int size = 128;
  CpuBackend cpu;
  const std::vector<Point> reference = testing::reference_inverse_grid(problem, size, size, 1e-9);
  auto worst_error = [&](const std::vector<Point>& grid) { return testing::max_difference(grid, reference); };

  CertifiedGridOptions options;
  options.tolerance_px = c.tolerance;
  WarpCertificate cert;
  const double lattice = worst_error(certified_inverse_map_grid(cpu, problem, size, size, options, {}, cert));
  std::cout << c.family << " " << c.count << " tolerance " << c.tolerance << ": measured " << lattice << " bound "
            << cert.max_error_px_bound << " check points " << cert.max_error_px_estimated << " sampled "
            << cert.max_error_px_sampled << (cert.exact ? " (exact)" : "") << " pixel pathlines "
            << cert.pixel_pathlines << "\n";
  EXPECT_LE(lattice, cert.max_error_px_bound);
  EXPECT_LE(cert.max_error_px_bound, c.tolerance);
  EXPECT_LE(cert.max_error_px_sampled, cert.max_error_px_bound);
  EXPECT_GT(cert.min_jacobian_det, 0.0);

  // --exact: every pixel by its own pathline, at the problem's tolerance, which the certificate reports.
  const double exact = worst_error(cpu.inverse_map_grid(problem, size, size, {}));
  const WarpCertificate exact_cert = exact_grid_certificate(cpu, problem, size, size, options, {});
  EXPECT_EQ(exact_cert.max_error_px_bound, o.tolerance_px);
  EXPECT_LE(exact, exact_cert.max_error_px_bound);
  EXPECT_GT(exact, 0.0);  // integrated to a tolerance, not exactly
  std::cout << "  exact: measured " << exact << " bound " << exact_cert.max_error_px_bound << "\n";
}

INSTANTIATE_TEST_SUITE_P(Families, CertificateBound,
                         ::testing::Values(BoundCase{"independent", 8, 0.05}, BoundCase{"independent", 20, 0.05},
                                           BoundCase{"smooth", 16, 0.05}, BoundCase{"smooth", 25, 0.01},
                                           BoundCase{"clustered", 12, 0.05}, BoundCase{"gradient", 9, 0.05},
                                           BoundCase{"independent", 12, 0.01}, BoundCase{"smooth", 49, 0.05},
                                           BoundCase{"clustered", 60, 0.05}, BoundCase{"clustered", 40, 0.01}),
                         [](const ::testing::TestParamInfo<BoundCase>& param_info) {
                           return std::string(param_info.param.family) + "_" + std::to_string(param_info.param.count) +
                                  "_tol_" + std::to_string(static_cast<int>(param_info.param.tolerance * 1000)) + "e_3";
                         });

// Failed cells whose split would cost more than their pixels' own pathlines keep those pathlines (issue 15):
// every pixel against the CPU reference at 1e-9, the bound above it; the profile accounts for every such pixel
// (cells of 4 px and more included, the new path), and the lattice still paid (fewer pathlines than pixels).
struct ProfileSums {
  std::size_t to_pixels_4_or_more = 0;
  std::size_t unsplit_pixels = 0;  // pixels of the cells sent to their own pathlines
  std::size_t lattice_pathlines = 0;
};

ProfileSums sums_of(const LatticeProfile& profile) {
  ProfileSums s;
  for (const LatticeLevel& l : profile.levels) {
    std::cout << "  cells of " << l.cell_px << " px: " << l.cells << ", failed " << l.failed_error << " + "
              << l.failed_fold << " (fold), split " << l.split << ", to pixels " << l.to_pixels << "; pathlines "
              << l.plain_pathlines << " + " << l.jacobian_pathlines << " with J\n";
    if (l.cell_px >= 4) s.to_pixels_4_or_more += l.to_pixels;
    s.unsplit_pixels += l.to_pixels * static_cast<std::size_t>(l.cell_px) * static_cast<std::size_t>(l.cell_px);
    s.lattice_pathlines += l.plain_pathlines + l.jacobian_pathlines;
    EXPECT_EQ(l.split + l.to_pixels, l.failed_error + l.failed_fold) << "cell " << l.cell_px;
    EXPECT_LE(l.failed_error + l.failed_fold, l.cells);
  }
  // Failed 8 px cells that the quartic on their 2 px grid held keep no pixel pathlines; its nodes' and checks' do
  // count among the lattice's.
  std::cout << "  failed 8 px cells on their 2 px grid: " << profile.fine_cells << ", accepted "
            << profile.fine_accepted << " (" << profile.fine_quick_accepted << " on their first checks); pathlines "
            << profile.fine_pathlines << "\n";
  EXPECT_LE(profile.fine_accepted, profile.fine_cells);
  EXPECT_LE(profile.fine_quick_accepted, profile.fine_accepted);
  s.unsplit_pixels -= profile.fine_accepted * 64;
  s.lattice_pathlines += profile.fine_pathlines;
  return s;
}

double worst_against_reference(const WarpProblem& problem, const std::vector<Point>& grid, int size) {
  return testing::max_difference(grid, testing::reference_inverse_grid(problem, size, size, 1e-9));
}

// The certified lattice on the CPU backend with default options, its profile recorded.
std::vector<Point> profiled_lattice(const WarpProblem& problem, int size, LatticeProfile& profile,
                                    WarpCertificate& cert) {
  CpuBackend cpu;
  CertifiedGridOptions options;
  options.profile = &profile;
  return certified_inverse_map_grid(cpu, problem, size, size, options, {}, cert);
}

TEST(CertifiedLattice, FailedCellsThatWouldNotPayKeepTheirPixelsPathlines) {
  WarpOptions o;
  const int size = 128;
  const WarpProblem problem(bound_case_features({"independent", 30, 0.05}, o), o);
  const CertifiedGridOptions options;  // the defaults profiled_lattice uses
  LatticeProfile profile;
  WarpCertificate cert;
  const std::vector<Point> grid = profiled_lattice(problem, size, profile, cert);
  const double measured = worst_against_reference(problem, grid, size);
  const ProfileSums sums = sums_of(profile);
  std::cout << "measured " << measured << " bound " << cert.max_error_px_bound << " pathlines " << cert.pathlines
            << " pixel pathlines " << cert.pixel_pathlines << " cells of ≥ 4 px to pixels " << sums.to_pixels_4_or_more
            << "\n";
  EXPECT_FALSE(profile.exact);
  EXPECT_FALSE(cert.exact);
  EXPECT_GT(sums.to_pixels_4_or_more, 0u);
  EXPECT_EQ(cert.pixel_pathlines, sums.unsplit_pixels);  // 128 = 2 × 64: every cell lies inside the image
  EXPECT_EQ(cert.pathlines, sums.lattice_pathlines + profile.pixel_pathlines + profile.sample_pathlines);
  // Never more pathlines than the exact path's: a pixel each and its certificate's sample.
  EXPECT_LE(cert.pathlines, static_cast<std::size_t>(size * size) + options.samples);
  EXPECT_LE(measured, cert.max_error_px_bound);
  EXPECT_LE(cert.max_error_px_bound, options.tolerance_px);
  EXPECT_GT(cert.min_jacobian_det, 0.0);
}

// The CPU backend, recording every batch it integrates: its start points, its tolerance, whether it carried the
// Jacobian.
class RecordingBackend final : public WarpBackend {
 public:
  struct Batch {
    std::vector<Point> starts;
    double tolerance_px;
    bool jacobian;
  };
  std::string name() const override { return "recording"; }
  void flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points, Direction direction,
                    const RunControl& control) override {
    batches.push_back({{points.begin(), points.end()}, problem.tolerance_px(), false});
    cpu_.flow_segment(problem, segment, points, direction, control);
  }
  void flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                  std::span<FlowJacobian> jacobians, Direction direction,
                                  const RunControl& control) override {
    batches.push_back({{points.begin(), points.end()}, problem.tolerance_px(), true});
    cpu_.flow_segment_with_jacobian(problem, segment, points, jacobians, direction, control);
  }
  std::vector<Batch> batches;

 private:
  CpuBackend cpu_;
};

// A pixel of a failed cell that keeps its own pathline has no interpolation error to leave room for: it is
// integrated as the exact path integrates every pixel, to the smaller of the problem's and the lattice's
// tolerances (here 0.01 px against 0.05), the nodes and the sample to 0.15 of the lattice's. The bound covers
// it, and holds against the reference at those pixels as everywhere.
TEST(CertifiedLattice, PixelsOfFailedCellsAreIntegratedAsTheExactPathWould) {
  WarpOptions o;  // tolerance_px 0.01
  const int size = 128;
  const WarpProblem problem(bound_case_features({"independent", 30, 0.05}, o), o);
  ASSERT_EQ(problem.segments().size(), 1u);
  RecordingBackend backend;
  CertifiedGridOptions options;  // tolerance_px 0.05
  LatticeProfile profile;
  options.profile = &profile;
  WarpCertificate cert;
  const std::vector<Point> grid = certified_inverse_map_grid(backend, problem, size, size, options, {}, cert);
  ASSERT_FALSE(cert.exact);
  ASSERT_GT(profile.pixel_pathlines, 0u);
  // Batches in order: each level's plain and Jacobian nodes and the quarter points of the cells those do not
  // settle (and the failed 8 px cells' 2 px grids), then the pixels, then the sample.
  ASSERT_GE(backend.batches.size(), 3u);
  const RecordingBackend::Batch& pixels = backend.batches[backend.batches.size() - 2];
  const RecordingBackend::Batch& sample = backend.batches.back();
  EXPECT_EQ(pixels.starts.size(), profile.pixel_pathlines);
  EXPECT_FALSE(pixels.jacobian);
  EXPECT_DOUBLE_EQ(pixels.tolerance_px, 0.01);
  EXPECT_EQ(sample.starts.size(), options.samples);
  EXPECT_DOUBLE_EQ(sample.tolerance_px, 0.0075);
  for (std::size_t b = 0; b + 2 < backend.batches.size(); ++b) {
    EXPECT_DOUBLE_EQ(backend.batches[b].tolerance_px, 0.0075);
  }
  EXPECT_GE(cert.max_error_px_bound, 0.01);
  EXPECT_LE(cert.max_error_px_bound, options.tolerance_px);
  // Against the reference at 1e-9: everywhere within the bound, and the pixels of that batch within their own
  // tolerance.
  const std::vector<Point> reference = testing::reference_inverse_grid(problem, size, size, 1e-9);
  EXPECT_LE(testing::max_difference(grid, reference), cert.max_error_px_bound);
  double own = 0.0;
  for (const Point c : pixels.starts) {
    const std::size_t i =
        static_cast<std::size_t>(std::floor(c.imag())) * size + static_cast<std::size_t>(std::floor(c.real()));
    own = std::max(own, std::abs(grid[i] - reference[i]));
  }
  std::cout << "pixels by their own pathline: " << pixels.starts.size() << ", worst " << own << " px\n";
  EXPECT_GT(own, 0.0);
  EXPECT_LE(own, 0.01);
}

// A cell of 4 px or more whose centre, edge midpoints and edges show it within a third of the tolerance is accepted
// on those; only the cells between that and the tolerance get their quarter points, in a batch of their own after
// the level's nodes, and every point of it is a quarter point of that level's cells. The bound (3 × the estimate of
// the cells accepted at once) holds at every pixel against the reference.
TEST(CertifiedLattice, CellsWellWithinTheToleranceAreAcceptedWithoutTheirQuarterPoints) {
  WarpOptions o;
  const int size = 128;
  for (const BoundCase& c : {BoundCase{"smooth", 49, 0.05}, BoundCase{"independent", 30, 0.05}}) {
    const WarpProblem problem(bound_case_features(c, o), o);
    RecordingBackend backend;
    CertifiedGridOptions options;
    LatticeProfile profile;
    options.profile = &profile;
    WarpCertificate cert;
    const std::vector<Point> grid = certified_inverse_map_grid(backend, problem, size, size, options, {}, cert);
    ASSERT_FALSE(cert.exact);
    std::size_t quick = 0, quarters = 0, batch = 0;
    // Each level's batches in order, those with no points absent: its plain nodes, its Jacobian nodes, the quarter
    // points of the cells those do not settle.
    auto next_batch = [&](std::size_t points, bool jacobian) -> const RecordingBackend::Batch* {
      if (points == 0) return nullptr;
      EXPECT_LT(batch, backend.batches.size());
      if (batch >= backend.batches.size()) return nullptr;
      const RecordingBackend::Batch& b = backend.batches[batch++];
      EXPECT_EQ(b.starts.size(), points);
      EXPECT_EQ(b.jacobian, jacobian);
      return &b;
    };
    for (const LatticeLevel& l : profile.levels) {
      std::cout << c.family << " " << c.count << ": cells of " << l.cell_px << " px: " << l.cells
                << ", accepted at once " << l.quick_accepted << ", quarter points for " << l.quarter_checked
                << ", failed " << l.failed_error << "\n";
      EXPECT_LE(l.quick_accepted + l.quarter_checked, l.cells);
      if (l.cell_px < 4) EXPECT_EQ(l.quick_accepted + l.quarter_checked, 0u);
      quick += l.quick_accepted;
      quarters += l.quarter_checked;
      ASSERT_GE(l.plain_pathlines, 4 * l.quarter_checked);
      const RecordingBackend::Batch* plain = next_batch(l.plain_pathlines - 4 * l.quarter_checked, false);
      const RecordingBackend::Batch* jacobian = next_batch(l.jacobian_pathlines, true);
      if (l.cell_px == 8) {
        // 8 px cells take their edge midpoints (4 px off the 8 px grid along one axis) plain: no such point carries a
        // Jacobian at that level, and they are among its plain nodes.
        auto edge_midpoint = [](Point p) {
          const int x = static_cast<int>(std::floor(p.real())), y = static_cast<int>(std::floor(p.imag()));
          return (x % 8 == 4 && y % 8 == 0) || (x % 8 == 0 && y % 8 == 4);
        };
        std::size_t plain_midpoints = 0;
        for (const Point p : plain ? plain->starts : std::vector<Point>{}) plain_midpoints += edge_midpoint(p);
        for (const Point p : jacobian ? jacobian->starts : std::vector<Point>{}) EXPECT_FALSE(edge_midpoint(p));
        EXPECT_GE(plain_midpoints, 2 * l.cells);  // a cell's four, each shared by at most two cells
      }
      const RecordingBackend::Batch* b = next_batch(4 * l.quarter_checked, false);
      const int q = l.cell_px / 4;
      for (const Point p : b ? b->starts : std::vector<Point>{}) {
        const int x = static_cast<int>(std::floor(p.real())), y = static_cast<int>(std::floor(p.imag()));
        EXPECT_TRUE(x % (2 * q) == q && y % (2 * q) == q) << "(" << x << ", " << y << ") at " << l.cell_px << " px";
      }
    }
    EXPECT_GT(quick, 0u);
    EXPECT_GT(quarters, 0u);
    const double measured = worst_against_reference(problem, grid, size);
    std::cout << "  measured " << measured << " bound " << cert.max_error_px_bound << " pathlines " << cert.pathlines
              << "\n";
    EXPECT_LE(measured, cert.max_error_px_bound);
    EXPECT_LE(cert.max_error_px_bound, options.tolerance_px);
  }
}

// A backend that returns one non-finite pathline end (or Jacobian) in its n-th batch: the lattice refuses it with
// a NumericalError naming the pixel, never interpolates from it nor outputs it (a NaN check point was the largest
// error of none, std::max dropping it, and its cell was accepted).
class PoisoningBackend final : public WarpBackend {
 public:
  PoisoningBackend(std::size_t batch, bool jacobian) : batch_(batch), jacobian_(jacobian) {}
  std::string name() const override { return "poisoning"; }
  void flow_segment(const WarpProblem& problem, std::size_t segment, std::span<Point> points, Direction direction,
                    const RunControl& control) override {
    cpu_.flow_segment(problem, segment, points, direction, control);
    if (!jacobian_ && batches_++ == batch_ && !points.empty()) points[points.size() / 2] = Point(std::nan(""), 0.0);
  }
  void flow_segment_with_jacobian(const WarpProblem& problem, std::size_t segment, std::span<Point> points,
                                  std::span<FlowJacobian> jacobians, Direction direction,
                                  const RunControl& control) override {
    cpu_.flow_segment_with_jacobian(problem, segment, points, jacobians, direction, control);
    if (jacobian_ && batches_++ == batch_ && !points.empty()) {
      jacobians[points.size() / 2].dx = Point(INFINITY, 0.0);
    }
  }

 private:
  CpuBackend cpu_;
  std::size_t batch_;
  bool jacobian_;
  std::size_t batches_ = 0;
};

TEST(CertifiedLattice, ANonFinitePathlineFromTheBackendIsRefusedNamingItsPixel) {
  WarpOptions o;
  const WarpProblem problem(bound_case_features({"independent", 8, 0.05}, o), o);
  for (const bool jacobian : {false, true}) {
    for (const std::size_t batch : {std::size_t{0}, std::size_t{1}}) {
      PoisoningBackend backend(batch, jacobian);
      WarpCertificate cert;
      try {
        certified_inverse_map_grid(backend, problem, 64, 64, CertifiedGridOptions{}, {}, cert);
        ADD_FAILURE() << "accepted a non-finite " << (jacobian ? "Jacobian" : "pathline") << " in batch " << batch;
      } catch (const NumericalError& e) {
        EXPECT_NE(std::string(e.what()).find("not finite at output pixel centre ("), std::string::npos) << e.what();
      }
    }
  }
}

// The same with planned trajectories (K > 1 segments, features swapping places): the lattice's pathlines and
// the pixels' own cross every segment.
TEST(CertifiedLattice, FailedCellsKeepTheirPixelsAcrossPlannedSegments) {
  const int size = 128;
  WarpOptions o;
  o.tolerance_px = 0.01;
  std::size_t exercised = 0;
  std::size_t fine_accepted = 0;
  std::size_t fine_quick = 0;
  std::size_t checked = 0;
  for (const testing::CrossingSet& set : testing::crossing_sets(size, false, o.tolerance_px)) {
    const WarpProblem problem(set.features, set.options);
    if (problem.segments().size() < 2) continue;
    if (++checked > 2) break;            // two sets (swap, rotated cluster): the reference at 1e-9 is slow
    const CertifiedGridOptions options;  // the defaults profiled_lattice uses
    LatticeProfile profile;
    WarpCertificate cert;
    const std::vector<Point> grid = profiled_lattice(problem, size, profile, cert);
    const double measured = worst_against_reference(problem, grid, size);
    const ProfileSums sums = sums_of(profile);
    std::cout << set.name << ": K = " << problem.segments().size() << ", measured " << measured << " bound "
              << cert.max_error_px_bound << ", cells of ≥ 4 px to pixels " << sums.to_pixels_4_or_more << "\n";
    EXPECT_LE(measured, cert.max_error_px_bound) << set.name;
    EXPECT_LE(cert.max_error_px_bound, options.tolerance_px) << set.name;
    if (!cert.exact) {
      EXPECT_EQ(cert.pixel_pathlines, sums.unsplit_pixels) << set.name;
    }
    exercised += sums.to_pixels_4_or_more;
    fine_accepted += profile.fine_accepted;
    fine_quick += profile.fine_quick_accepted;
  }
  EXPECT_GT(exercised, 0u);
  // Failed 8 px cells held by the quartic on their 2 px grid, within the bound too: on their first checks alone,
  // and on all of them.
  EXPECT_GT(fine_quick, 0u);
  EXPECT_GT(fine_accepted, fine_quick);
}

TEST(Baselines, InterpolateTheFeatures) {
  const WarpProblem problem = random_problem(10, 0, 11);
  for (const WarpMethod m : {WarpMethod::kThinPlateSpline, WarpMethod::kMovingLeastSquares}) {
    const auto fwd = baseline_map(m, problem, false);
    const auto inv = baseline_map(m, problem, true);
    for (const Feature& f : problem.features()) {
      EXPECT_LE(std::abs(fwd(f.source) - f.target), 1e-6) << to_string(m);
      EXPECT_LE(std::abs(inv(f.target) - f.source), 1e-6) << to_string(m);
    }
  }
}

// At texture scale (thousands of pixels) the spline's system mixes kernel entries of ~1e8 with the affine
// block's ones; it must still be solved (it was once refused as "collinear"), reproduce an affine map exactly
// and interpolate its points.
TEST(Baselines, ThinPlateSplineAtTextureScale) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double size = 8192.0;
  std::vector<Point> src;
  src.reserve(60);
  for (int k = 0; k < 60; ++k) src.emplace_back(size * unit(rng), size * unit(rng));
  const Point a(0.9, 0.3);  // z ↦ a·z + b·conj(z) + c: a general affine map
  const Point b(0.05, -0.1);
  const Point c(120.0, -40.0);
  auto affine = [&](Point p) { return a * p + b * std::conj(p) + c; };
  std::vector<Point> dst;
  dst.reserve(src.size());
  for (const Point& p : src) dst.push_back(affine(p));
  const ThinPlateSpline flat(src, dst);
  for (int k = 0; k < 200; ++k) {
    const Point p(size * unit(rng), size * unit(rng));
    EXPECT_LE(std::abs(flat(p) - affine(p)), 1e-6 * size);
  }
  std::vector<Point> moved;
  moved.reserve(dst.size());
  for (const Point& p : dst) moved.push_back(p + Point(200.0 * unit(rng) - 100.0, 200.0 * unit(rng) - 100.0));
  const ThinPlateSpline bent(src, moved);
  for (std::size_t k = 0; k < src.size(); ++k) EXPECT_LE(std::abs(bent(src[k]) - moved[k]), 1e-6 * size);
}

TEST(Baselines, MovingLeastSquaresOfASimilarityIsThatSimilarity) {
  // Independent value: when the targets are one similarity of the sources, every weighted fit is that
  // similarity, at every point.
  const Point a = std::polar(1.3, 0.4);
  const Point b(7.0, -2.0);
  std::vector<Point> src = {{0, 0}, {50, 10}, {20, 40}, {-10, 30}};
  std::vector<Point> dst;
  dst.reserve(src.size());
  for (Point p : src) dst.push_back(a * p + b);
  const MovingLeastSquares mls(src, dst);
  for (const Point v : {Point(5, 5), Point(-30, 80), Point(49, 11)}) EXPECT_LE(std::abs(mls(v) - (a * v + b)), 1e-9);
}

}  // namespace
}  // namespace texwarp
