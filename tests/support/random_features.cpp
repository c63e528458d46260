// Random valid feature sets: see random_features.hpp.
#include "random_features.hpp"

#include <algorithm>
#include <random>
#include <stdexcept>

#include "texwarp/core/warp_problem.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::testing {

std::vector<Feature> random_features(const RandomFeatureSpec& spec, const WarpOptions& options) {
  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> ux(spec.margin, spec.width - spec.margin);
  std::uniform_real_distribution<double> uy(spec.margin, spec.height - spec.margin);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Feature> features;
  for (int i = 0; i < spec.count; ++i) {
    const bool gradient = i < spec.gradient_count;
    bool placed = false;
    for (int attempt = 0; attempt < 1000 && !placed; ++attempt) {
      Feature f;
      f.id = "f" + std::to_string(i);
      f.source = Point(ux(rng), uy(rng));
      Point d;
      do {
        d = Point(unit(rng), unit(rng));
      } while (std::abs(d) > 1.0);
      f.target = f.source + spec.max_displacement * d;
      f.target = Point(std::clamp(f.target.real(), spec.margin, spec.width - spec.margin),
                       std::clamp(f.target.imag(), spec.margin, spec.height - spec.margin));
      if (gradient) {
        const double a0 = 3.14159265358979 * unit(rng);
        f.source_frame = Frame{a0, std::exp(0.5 * unit(rng))};
        f.target_frame = Frame{a0 + spec.max_rotation_deg * 3.14159265358979 / 180.0 * unit(rng),
                               f.source_frame->scale * std::exp(spec.max_log_scale * unit(rng))};
      }
      features.push_back(f);
      try {
        // Valid with straight trajectories: the sets these tests and benchmarks were written for.
        WarpProblem check(features, options);
        placed = !check.trajectory_plan().straight_collides;
        if (!placed) features.pop_back();
      } catch (const InputError&) {
        features.pop_back();
      }
    }
    if (!placed) throw std::runtime_error("random_features: could not place feature " + std::to_string(i));
  }
  return features;
}

}  // namespace texwarp::testing
