// Warped images through the OpenCL backend against the CPU path's image: PSNR ≥ 60 dB, per-pixel pathlines
// (exact) and the certified lattice, whose nodes come from the backend's flow Jacobians.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <vector>

#include "kernel_test_support.hpp"
#include "reference_grid.hpp"
#include "texwarp/core/certified_warp.hpp"
#include "texwarp/core/cpu_backend.hpp"
#include "texwarp/core/image_warp.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {
namespace {

// A smooth RGB test texture with detail at several scales, values in [0, 1].
Image test_texture(int width, int height) {
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      float* p = image.pixel(x, y);
      p[0] = static_cast<float>(0.5 + 0.5 * std::sin(0.21 * x) * std::cos(0.17 * y));
      p[1] = static_cast<float>((x + 2 * y) % 23) / 22.0f;
      p[2] = static_cast<float>(x) / static_cast<float>(width - 1);
    }
  }
  return image;
}

// Peak signal-to-noise ratio for a peak of 1 over every channel; +∞ for equal images, NaN-safe (→ 0 dB).
double psnr(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.channels != b.channels) return 0.0;
  double sum = 0.0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    const double d = static_cast<double>(a.pixels[i]) - static_cast<double>(b.pixels[i]);
    if (!std::isfinite(d)) return 0.0;
    sum += d * d;
  }
  if (sum == 0.0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(static_cast<double>(a.pixels.size()) / sum);
}

TEST(OpenClImage, ExactWarpMatchesTheCpuImage) {
  const WarpProblem problem = testing::make_problem(testing::spec(20, 3, 2.0, 1e-3, 97.0, 61.0, 41));
  const Image source = test_texture(97, 61);
  ImageWarpOptions options;
  options.exact = true;
  options.interpolation = Interpolation::kBicubic;
  OpenClWarpBackend opencl;
  CpuBackend cpu;
  const Image a = warp_image(opencl, problem, source, options);
  const Image b = warp_image(cpu, problem, source, options);
  EXPECT_GE(psnr(a, b), 60.0);
}

TEST(OpenClImage, CertifiedLatticeWarpMatchesTheCpuImage) {
  const WarpProblem problem = testing::make_problem(testing::spec(15, 2, 2.0, 1e-2, 128.0, 96.0, 42));
  const Image source = test_texture(128, 96);
  ImageWarpOptions options;  // the certified lattice
  options.tolerance_px = 0.01;
  OpenClWarpBackend opencl;
  CpuBackend cpu;
  WarpCertificate ca, cb;
  const Image a = warp_image(opencl, problem, source, options, {}, &ca);
  const Image b = warp_image(cpu, problem, source, options, {}, &cb);
  EXPECT_GE(psnr(a, b), 60.0);
  EXPECT_EQ(ca.nonpositive_jacobians, 0u);
  EXPECT_LE(ca.max_error_px_sampled, options.tolerance_px);
}

// A dense independent set (issue 15): failed cells of 4 px and more keep their pixels' own pathlines, integrated
// by the OpenCL backend in one batch; every pixel against the CPU reference at 1e-7 (far below the bound, and
// quicker than 1e-9) stays within the certificate's bound.
TEST(OpenClImage, CertifiedLatticeFailedCellsKeepTheirPixelsWithinTheBound) {
  const int size = 128;
  const WarpProblem problem = testing::make_problem(testing::spec(20, 0, 2.0, 1e-2, size, size, 43));
  OpenClWarpBackend opencl;
  LatticeProfile profile;
  CertifiedGridOptions options;
  options.profile = &profile;
  WarpCertificate cert;
  const std::vector<Point> grid = certified_inverse_map_grid(opencl, problem, size, size, options, {}, cert);
  const double worst = testing::max_difference(grid, testing::reference_inverse_grid(problem, size, size, 1e-7));
  std::size_t to_pixels = 0;
  for (const LatticeLevel& l : profile.levels) to_pixels += l.cell_px >= 4 ? l.to_pixels : 0;
  std::cout << "measured " << worst << " bound " << cert.max_error_px_bound << ", cells of >= 4 px to pixels "
            << to_pixels << ", pixel pathlines " << cert.pixel_pathlines << "\n";
  EXPECT_FALSE(cert.exact);
  EXPECT_GT(to_pixels, 0u);
  EXPECT_LE(worst, cert.max_error_px_bound);
  EXPECT_LE(cert.max_error_px_bound, options.tolerance_px);
  EXPECT_EQ(cert.nonpositive_jacobians, 0u);
}

}  // namespace
}  // namespace texwarp
