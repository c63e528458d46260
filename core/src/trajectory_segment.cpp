// One straight segment of the features' trajectories: see trajectory_segment.hpp.
#include "texwarp/core/trajectory_segment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace texwarp {

PairApproach straight_closest_approach(Point x0, Point dx, Point y0, Point dy) {
  const Point r0 = y0 - x0;
  const Point dr = dy - dx;
  const double dr2 = std::norm(dr);
  double t = 0.0;
  if (dr2 > 0.0) t = std::clamp(-(r0.real() * dr.real() + r0.imag() * dr.imag()) / dr2, 0.0, 1.0);
  return {t, std::abs(r0 + t * dr)};
}

double median_nearest_distance(std::span<const Point> from, std::span<const Point> to) {
  const std::size_t n = from.size();
  if (n < 2) return 1.0;
  std::vector<double> nearest(n);
  for (std::size_t i = 0; i < n; ++i) {
    double start = std::numeric_limits<double>::infinity();
    double end = start;
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      start = std::min(start, std::abs(from[i] - from[j]));
      end = std::min(end, std::abs(to[i] - to[j]));
    }
    nearest[i] = 0.5 * (start + end);
  }
  std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(n / 2), nearest.end());
  const double median = nearest[n / 2];
  return median > 0.0 ? median : 1.0;
}

TrajectorySegment make_segment(std::span<const Point> from, std::span<const Point> to, std::span<const Point> rates,
                               const std::vector<bool>& gradient, double t_begin, double t_end,
                               double weight_length_px) {
  TrajectorySegment s;
  s.weight_length_px = weight_length_px;
  const double duration = t_end - t_begin;
  for (std::size_t i = 0; i < from.size(); ++i) {
    const Point velocity = to[i] - from[i];
    if (gradient[i]) {
      const Point rate = rates[i] == Point(0.0) ? Point(0.0) : rates[i] * duration;
      s.gradient.push_back({from[i], velocity, rate, i});
      if (std::abs(rate) * s.time_scale > 1.0) s.time_scale = 1.0 / std::abs(rate);
      if (velocity != 0.0 || rate != 0.0) s.field_is_zero = false;
    } else {
      s.positional.push_back({from[i], velocity, i});
      if (velocity != 0.0) s.field_is_zero = false;
    }
  }
  // Exact closest approach per pair; positional features first, then gradient ones (ties go to the first found).
  struct Moving {
    Point start;
    Point velocity;
    std::size_t feature;
  };
  std::vector<Moving> all;
  for (const auto& p : s.positional) all.push_back({p.start, p.velocity, p.feature});
  for (const auto& g : s.gradient) all.push_back({g.start, g.velocity, g.feature});
  s.closest.distance_px = std::numeric_limits<double>::infinity();
  for (std::size_t a = 0; a < all.size(); ++a) {
    for (std::size_t b = a + 1; b < all.size(); ++b) {
      const auto [t, distance] =
          straight_closest_approach(all[a].start, all[a].velocity, all[b].start, all[b].velocity);
      if (distance < s.closest.distance_px) {
        s.closest = {std::min(all[a].feature, all[b].feature), std::max(all[a].feature, all[b].feature),
                     t_begin + t * duration, distance};
      }
      const double relative_speed = std::abs(all[b].velocity - all[a].velocity);
      if (distance < s.time_scale * relative_speed) s.time_scale = distance / relative_speed;
      if (t > 0.0 && t < 1.0 && distance < kNearCollisionMaxTau * relative_speed) {
        s.near_collisions.push_back({t, kNearCollisionWidthFactor * distance / relative_speed});
      }
    }
  }
  std::sort(s.near_collisions.begin(), s.near_collisions.end(),
            [](const NearCollision& x, const NearCollision& y) { return x.t < y.t; });
  return s;
}

}  // namespace texwarp
