// Validation and preparation of a warp's features: see warp_problem.hpp.
#include "texwarp/core/warp_problem.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

#include "texwarp/proto/input_error.hpp"

namespace texwarp {
namespace {

bool finite(Point z) { return std::isfinite(z.real()) && std::isfinite(z.imag()); }

// `feature "id": ` for a message about a feature that has an id (its JSON path names its place), else "".
std::string feature_name(const Feature& f) { return f.id.empty() ? std::string() : "feature \"" + f.id + "\": "; }

std::string format_point(Point z) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g)", z.real(), z.imag());
  return buf;
}

std::string format_number(double x) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

// Wraps an angle to (−π, π]: a gradient feature turns the short way round.
double wrap_angle(double a) {
  const double two_pi = 2.0 * std::numbers::pi;
  a = std::fmod(a, two_pi);
  if (a <= -std::numbers::pi) a += two_pi;
  if (a > std::numbers::pi) a -= two_pi;
  return a;
}

// Closest approach of two straight trajectories x(t) = x0 + t·dx, y(t) = y0 + t·dy over t ∈ [0, 1]:
// returns (t*, distance).
std::pair<double, double> trajectory_closest_approach(Point x0, Point dx, Point y0, Point dy) {
  const Point r0 = y0 - x0;
  const Point dr = dy - dx;
  const double dr2 = std::norm(dr);
  double t = 0.0;
  if (dr2 > 0.0) t = std::clamp(-(r0.real() * dr.real() + r0.imag() * dr.imag()) / dr2, 0.0, 1.0);
  return {t, std::abs(r0 + t * dr)};
}

// The median over features of the distance to the nearest other feature, averaged over the trajectory's ends.
double median_nearest_distance(const std::vector<Feature>& features, const Similarity& prealignment) {
  const std::size_t n = features.size();
  if (n < 2) return 1.0;
  std::vector<double> nearest(n);
  for (std::size_t i = 0; i < n; ++i) {
    double start = std::numeric_limits<double>::infinity();
    double end = start;
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      start = std::min(start, std::abs(prealignment(features[i].source) - prealignment(features[j].source)));
      end = std::min(end, std::abs(features[i].target - features[j].target));
    }
    nearest[i] = 0.5 * (start + end);
  }
  std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(n / 2), nearest.end());
  const double median = nearest[n / 2];
  return median > 0.0 ? median : 1.0;
}

}  // namespace

WarpProblem::WarpProblem(std::vector<Feature> features, WarpOptions options)
    : features_(std::move(features)), options_(options) {
  validate();
  build();
  check_collisions();
}

void WarpProblem::validate() const {
  const auto& o = options_;
  if (!std::isfinite(o.alpha) || o.alpha <= 0.0 || o.alpha > kMaxAlpha) {
    throw InputError(JsonPath{"alpha"}, "alpha must be in (0, " + format_number(kMaxAlpha) + "], got " +
                                            format_number(o.alpha) + " (2 is the paper's default; C¹ needs alpha > 1)");
  }
  if (!std::isfinite(o.tolerance_px) || o.tolerance_px < kMinTolerancePx) {
    throw InputError(JsonPath{"tolerance_px"}, "tolerance_px must be a finite number ≥ " +
                                                   format_number(kMinTolerancePx) + ", got " +
                                                   format_number(o.tolerance_px));
  }
  if (!std::isfinite(o.min_separation_px) || o.min_separation_px <= 0.0) {
    throw InputError(JsonPath{"min_separation_px"},
                     "must be a finite number > 0, got " + format_number(o.min_separation_px));
  }
  for (std::size_t i = 0; i < features_.size(); ++i) {
    const Feature& f = features_[i];
    const JsonPath where = JsonPath{"features"}.index(i);
    const std::string named = feature_name(f);
    if (!finite(f.source)) throw InputError(where, named + "source is not a finite point");
    if (!finite(f.target)) throw InputError(where, named + "target is not a finite point");
    if (f.source_frame.has_value() != f.target_frame.has_value()) {
      throw InputError(where, named + "a gradient feature needs both a source frame and a target frame");
    }
    for (const auto* frame : {&f.source_frame, &f.target_frame}) {
      if (!frame->has_value()) continue;
      const char* which = frame == &f.source_frame ? "source_frame" : "target_frame";
      if (!std::isfinite((*frame)->angle_rad)) throw InputError(where, named + which + " angle is not finite");
      if (!std::isfinite((*frame)->scale) || (*frame)->scale <= 0.0) {
        throw InputError(where,
                         named + which + " scale must be a finite number > 0, got " + format_number((*frame)->scale));
      }
    }
  }
  // Duplicate positions: exact equality (near-duplicates are collisions at t = 0 or 1, reported below).
  for (const bool sources : {true, false}) {
    std::map<std::pair<double, double>, std::size_t> seen;
    for (std::size_t i = 0; i < features_.size(); ++i) {
      const Point z = sources ? features_[i].source : features_[i].target;
      const auto [it, inserted] = seen.emplace(std::make_pair(z.real(), z.imag()), i);
      if (!inserted) {
        throw InputError(JsonPath{"features"}.index(i),
                         feature_name(features_[i]) + "duplicate " + (sources ? "source" : "target") + " position " +
                             format_point(z) + ": " + describe_feature(features_, it->second) + " has the same one");
      }
    }
  }
}

void WarpProblem::build() {
  std::vector<Point> src;
  std::vector<Point> dst;
  for (const Feature& f : features_) {
    src.push_back(f.source);
    dst.push_back(f.target);
  }
  if (options_.prealign == Prealign::kSimilarity) prealignment_ = fit_similarity(src, dst);

  weight_length_px_ = median_nearest_distance(features_, prealignment_);

  std::size_t positional_count = 0;
  for (const Feature& f : features_) positional_count += f.is_gradient() ? 0 : 1;

  for (std::size_t i = 0; i < features_.size(); ++i) {
    const Feature& f = features_[i];
    const Point start = prealignment_(f.source);
    const Point velocity = f.target - start;
    if (f.is_gradient() || positional_count == 1) {
      // A lone positional feature has no pair: it becomes a gradient feature with φ = 0, S = 1 (a translation).
      Point rate = 0.0;
      if (f.is_gradient()) {
        const double source_angle = f.source_frame->angle_rad + prealignment_.angle_rad();
        const double source_scale = f.source_frame->scale * prealignment_.scale();
        rate =
            Point(std::log(f.target_frame->scale / source_scale), wrap_angle(f.target_frame->angle_rad - source_angle));
      }
      gradient_.push_back({start, velocity, rate, i});
      if (velocity != 0.0 || rate != 0.0) field_is_zero_ = false;
    } else {
      positional_.push_back({start, velocity, i});
      if (velocity != 0.0) field_is_zero_ = false;
    }
  }
}

void WarpProblem::check_collisions() {
  struct Moving {
    Point start;
    Point velocity;
    std::size_t feature;
  };
  closest_.distance_px = std::numeric_limits<double>::infinity();
  std::vector<Moving> all;
  for (const auto& p : positional_) all.push_back({p.start, p.velocity, p.feature});
  for (const auto& g : gradient_) all.push_back({g.start, g.velocity, g.feature});
  for (std::size_t a = 0; a < all.size(); ++a) {
    for (std::size_t b = a + 1; b < all.size(); ++b) {
      const auto [t, distance] =
          trajectory_closest_approach(all[a].start, all[a].velocity, all[b].start, all[b].velocity);
      const std::size_t i = std::min(all[a].feature, all[b].feature);
      const std::size_t j = std::max(all[a].feature, all[b].feature);
      if (distance < closest_.distance_px) closest_ = {i, j, t, distance};
      const double relative_speed = std::abs(all[b].velocity - all[a].velocity);
      if (t > 0.0 && t < 1.0 && distance < kNearCollisionMaxTau * relative_speed) {
        near_collisions_.push_back({t, kNearCollisionWidthFactor * distance / relative_speed});
      }
      if (distance < options_.min_separation_px) {
        std::string msg = describe_feature(features_, i) + " and " + describe_feature(features_, j) +
                          " collide at t = " + format_number(t) + ": their trajectories come within " +
                          format_number(distance) + " px of each other (minimum " +
                          format_number(options_.min_separation_px) + " px)";
        msg += options_.prealign == Prealign::kSimilarity
                   ? " after pre-alignment; move one of them, or try prealign \"none\""
                   : "; move one of them, or try prealign \"similarity\"";
        throw InputError(JsonPath{"features"}, msg);
      }
    }
  }
  std::sort(near_collisions_.begin(), near_collisions_.end(),
            [](const NearCollision& x, const NearCollision& y) { return x.t < y.t; });
}

}  // namespace texwarp
