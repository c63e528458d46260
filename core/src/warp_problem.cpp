// Validation and preparation of a warp's features: see warp_problem.hpp.
#include "texwarp/core/warp_problem.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

#include "texwarp/core/flow_growth.hpp"
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

}  // namespace

WarpProblem::WarpProblem(std::vector<Feature> features, WarpOptions options)
    : features_(std::move(features)), options_(options), growth_(std::make_shared<FlowGrowthCache>()) {
  validate();
  build();
}

WarpProblem WarpProblem::with_tolerance(double tolerance_px) const {
  validate_tolerance(tolerance_px);
  WarpProblem out = *this;
  out.options_.tolerance_px = tolerance_px;
  return out;
}

double WarpProblem::pathline_tolerance_px(Direction direction) const {
  const double where_it_lands = direction == Direction::kForward
                                    ? options_.tolerance_px
                                    : options_.tolerance_px * std::min(1.0, std::abs(prealignment_.a));
  // The growth scale never takes it below the smallest tolerance a problem accepts (double's reach).
  return std::max(where_it_lands * growth_scale(direction), std::min(where_it_lands, kMinTolerancePx));
}

double WarpProblem::growth_scale(Direction direction) const {
  return growth_->scale[direction == Direction::kForward ? 0 : 1].load();
}

void WarpProblem::validate_tolerance(double tolerance_px) {
  if (!std::isfinite(tolerance_px) || tolerance_px < kMinTolerancePx) {
    throw InputError(JsonPath{"tolerance_px"}, "tolerance_px must be a finite number ≥ " +
                                                   format_number(kMinTolerancePx) + ", got " +
                                                   format_number(tolerance_px));
  }
}

void WarpProblem::validate() const {
  const auto& o = options_;
  if (!std::isfinite(o.alpha) || o.alpha <= 0.0 || o.alpha > kMaxAlpha) {
    throw InputError(JsonPath{"alpha"}, "alpha must be in (0, " + format_number(kMaxAlpha) + "], got " +
                                            format_number(o.alpha) + " (2 is the paper's default; C¹ needs alpha > 1)");
  }
  validate_tolerance(o.tolerance_px);
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

  std::size_t positional_count = 0;
  for (const Feature& f : features_) positional_count += f.is_gradient() ? 0 : 1;

  // Per feature: its pre-aligned start, whether it moves as a gradient feature, and its whole rate κ.
  std::vector<Point> starts;
  std::vector<Point> rates;
  std::vector<bool> gradient(features_.size(), false);
  auto prepare = [&] {
    starts.clear();
    rates.assign(features_.size(), Point(0.0));
    for (std::size_t i = 0; i < features_.size(); ++i) {
      const Feature& f = features_[i];
      starts.push_back(prealignment_(f.source));
      if (f.is_gradient() || positional_count == 1) {
        // A lone positional feature has no pair: it becomes a gradient feature with φ = 0, S = 1 (a translation).
        gradient[i] = true;
        if (f.is_gradient()) {
          const double source_angle = f.source_frame->angle_rad + prealignment_.angle_rad();
          const double source_scale = f.source_frame->scale * prealignment_.scale();
          rates[i] = Point(std::log(f.target_frame->scale / source_scale),
                           wrap_angle(f.target_frame->angle_rad - source_angle));
        }
      }
    }
    // Lowered below, once the pre-alignment is final.
    plan_ = plan_trajectories(starts, dst, options_.min_separation_px, median_nearest_distance(starts, dst), false);
  };
  prepare();
  // Sets whose straight trajectories collide often fit a shrinking S (a permutation's best similarity is close to a
  // point): one that would squeeze the sources below the minimum, or to less than half their size, is relaxed to
  // that scale (its angle kept, its translation refitted) before planning. Straight sets keep their S unchanged.
  if (plan_.straight_collides && prealignment_.scale() < kMinPlannedPrealignScale) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < src.size(); ++i) {
      for (std::size_t j = i + 1; j < src.size(); ++j) nearest = std::min(nearest, std::abs(src[i] - src[j]));
    }
    const double scale = std::max(kMinPlannedPrealignScale, 2.0 * options_.min_separation_px / nearest);
    Point mean_src = 0.0;
    Point mean_dst = 0.0;
    for (std::size_t i = 0; i < src.size(); ++i) {
      mean_src += src[i] / static_cast<double>(src.size());
      mean_dst += dst[i] / static_cast<double>(src.size());
    }
    const Point a = std::polar(std::min(scale, 1.0), prealignment_.angle_rad());
    prealignment_ = Similarity{a, mean_dst - a * mean_src};
    prepare();
  }
  if (options_.lower_energy) {
    plan_ = lower_trajectory_energy(plan_, options_.min_separation_px, median_nearest_distance(starts, dst),
                                    options_.widen_near_misses);
  }

  closest_.distance_px = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < plan_.segments(); ++k) {
    const auto& from = plan_.waypoints[k];
    const auto& to = plan_.waypoints[k + 1];
    segments_.push_back(
        make_segment(from, to, rates, gradient, plan_.knots[k], plan_.knots[k + 1], median_nearest_distance(from, to)));
    if (!segments_.back().field_is_zero) field_is_zero_ = false;
    if (segments_.back().closest.distance_px < closest_.distance_px) closest_ = segments_.back().closest;
  }
  if (closest_.distance_px < options_.min_separation_px) {
    // Only sources (or targets) closer than the minimum leave the planner short of it.
    const std::size_t i = closest_.first;
    const std::size_t j = closest_.second;
    std::string msg = describe_feature(features_, i) + " and " + describe_feature(features_, j) + " come within " +
                      format_number(closest_.distance_px) + " px of each other at t = " + format_number(closest_.t) +
                      " (minimum " + format_number(options_.min_separation_px) + " px";
    msg += options_.prealign == Prealign::kSimilarity ? ", after pre-alignment)" : ")";
    msg += ", and no trajectories can keep them apart: move one of them, or lower min_separation_px";
    throw InputError(JsonPath{"features"}, msg);
  }
}

}  // namespace texwarp
