// The warm-up launch of a kernel variant: see kernel_warmup.hpp.
#include "kernel_warmup.hpp"

#include <vector>

#include "pathline_launcher.hpp"

namespace texwarp::kernels_detail {
namespace {

// Three features whose displacements no similarity fits: the field is not zero, so the kernel runs.
WarpProblem tiny_problem() {
  std::vector<Feature> features(3);
  features[0].source = {8.0, 8.0};
  features[0].target = {9.0, 8.5};
  features[1].source = {24.0, 8.0};
  features[1].target = {23.5, 9.0};
  features[2].source = {16.0, 20.0};
  features[2].target = {16.5, 19.0};
  return WarpProblem(std::move(features), WarpOptions{});
}

template <class Real>
void launch(const DeviceHandle& device, const WarpProblem& problem, bool with_jacobian) {
  auto fill = [](TileData<Real>& tile) {
    for (std::size_t k = 0; k < tile.count * kPointsPerItem; ++k) {
      tile.origin_x[k] = static_cast<Real>(10 + k % 8);
      tile.origin_y[k] = static_cast<Real>(10 + k / 8 % 8);
      tile.offset_x[k] = Real(0);
      tile.offset_y[k] = Real(0);
    }
  };
  auto take = [](const TileData<Real>&) {};
  OpenClRunStats stats;
  PathlineLauncher<Real>(device, problem, 0, Direction::kInverse, with_jacobian).run(1, fill, take, {}, stats);
}

}  // namespace

void launch_variant_once(const DeviceHandle& device, KernelVariant variant) {
  const WarpProblem problem = tiny_problem();
  if (variant.double_precision) {
    launch<double>(device, problem, variant.jacobian);
  } else {
    launch<float>(device, problem, variant.jacobian);
  }
}

}  // namespace texwarp::kernels_detail
