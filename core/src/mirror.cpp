// Mirrored feature sets: see mirror.hpp.
#include "texwarp/core/mirror.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace texwarp {

MirrorFit fit_mirror(std::span<const Feature> features) {
  MirrorFit fit;
  const std::size_t n = features.size();
  if (n == 0) return fit;
  Point mean_p(0.0, 0.0), mean_q(0.0, 0.0);
  for (const Feature& f : features) {
    mean_p += f.source;
    mean_q += f.target;
  }
  mean_p /= static_cast<double>(n);
  mean_q /= static_cast<double>(n);
  // Centred: the proper fit a = Σ conj(p)·q / Σ|p|² leaves Σ|q|² − |Σ conj(p)·q|² / Σ|p|²; the reflected one
  // (p replaced by conj(p)) leaves Σ|q|² − |Σ p·q|² / Σ|p|².
  double pp = 0.0, qq = 0.0;
  Point proper(0.0, 0.0), reflected(0.0, 0.0);
  for (const Feature& f : features) {
    const Point p = f.source - mean_p, q = f.target - mean_q;
    pp += std::norm(p);
    qq += std::norm(q);
    proper += std::conj(p) * q;
    reflected += p * q;
  }
  fit.proper_residual = pp > 0.0 ? std::max(0.0, qq - std::norm(proper) / pp) : qq;
  fit.reflected_residual = pp > 0.0 ? std::max(0.0, qq - std::norm(reflected) / pp) : qq;
  if (n >= 3 && fit.proper_residual > 0.0) {
    fit.residual_ratio = fit.reflected_residual / fit.proper_residual;
    fit.mirrored = fit.residual_ratio < kMirrorResidualRatio;
  }
  return fit;
}

std::vector<Feature> mirror_features(std::vector<Feature> features, double width) {
  for (Feature& f : features) {
    f.source = Point(width - f.source.real(), f.source.imag());
    if (f.source_frame) f.source_frame->angle_rad = std::numbers::pi - f.source_frame->angle_rad;
  }
  return features;
}

proto::MirrorReport mirror_report(std::span<const Feature> features, bool applied) {
  const MirrorFit fit = fit_mirror(features);
  proto::MirrorReport r;
  r.detected = fit.mirrored;
  r.residual_ratio = fit.residual_ratio;
  r.applied = applied;
  if (fit.mirrored && !applied) r.suggestion = kMirrorSuggestion;
  return r;
}

void mirror_image(Image& image) {
  const auto c = static_cast<std::size_t>(image.channels);
  const auto w = static_cast<std::size_t>(image.width);
  for (std::size_t y = 0; y < static_cast<std::size_t>(image.height); ++y) {
    float* row = image.pixels.data() + y * w * c;
    for (std::size_t x = 0; x < w / 2; ++x) std::swap_ranges(row + x * c, row + (x + 1) * c, row + (w - 1 - x) * c);
  }
}

}  // namespace texwarp
