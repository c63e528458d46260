// Placement of an embedding into the texture frame: see frame_placement.hpp.
#include "texwarp/mesh/frame_placement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "texwarp/core/numerical_error.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {
namespace {

double cross(Point o, Point a, Point b) {
  return (a.real() - o.real()) * (b.imag() - o.imag()) - (a.imag() - o.imag()) * (b.real() - o.real());
}

// Convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
std::vector<Point> convex_hull(std::span<const Point> points) {
  std::vector<Point> p(points.begin(), points.end());
  std::sort(p.begin(), p.end(),
            [](Point a, Point b) { return a.real() < b.real() || (a.real() == b.real() && a.imag() < b.imag()); });
  std::vector<Point> hull(2 * p.size());
  std::size_t k = 0;
  for (const Point& q : p) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], q) <= 0.0) --k;
    hull[k++] = q;
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], p[i]) <= 0.0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k > 1 ? k - 1 : k);
  return hull;
}

// Largest uniform scale at which `points` rotated by `angle` fit a room_w × room_h box.
double fit_scale(const std::vector<Point>& points, double angle, double room_w, double room_h) {
  const Point rot = std::polar(1.0, angle);
  double min_x = std::numeric_limits<double>::infinity(), max_x = -min_x, min_y = min_x, max_y = -min_x;
  for (Point p : points) {
    const Point q = rot * p;
    min_x = std::min(min_x, q.real());
    max_x = std::max(max_x, q.real());
    min_y = std::min(min_y, q.imag());
    max_y = std::max(max_y, q.imag());
  }
  const double sx = max_x > min_x ? room_w / (max_x - min_x) : std::numeric_limits<double>::infinity();
  const double sy = max_y > min_y ? room_h / (max_y - min_y) : std::numeric_limits<double>::infinity();
  return std::min(sx, sy);
}

}  // namespace

FramePlacement place_in_frame(std::span<const Point> embedding, const FramePlacementOptions& options) {
  if (options.width <= 0 || options.height <= 0) {
    throw InputError({}, "the texture frame must have a positive size, got " + std::to_string(options.width) + "×" +
                             std::to_string(options.height));
  }
  const double room_w = options.width - 2.0 * options.margin_px;
  const double room_h = options.height - 2.0 * options.margin_px;
  if (!(options.margin_px >= 0.0) || room_w <= 0.0 || room_h <= 0.0) {
    throw InputError({}, "a margin of " + std::to_string(options.margin_px) + " px leaves no room in a " +
                             std::to_string(options.width) + "×" + std::to_string(options.height) + " frame");
  }
  FramePlacement out;
  if (options.rotate_to_fit && embedding.size() >= 3) {
    const std::vector<Point> hull = convex_hull(embedding);
    double best_scale = fit_scale(hull, 0.0, room_w, room_h);
    for (std::size_t i = 0; i < hull.size(); ++i) {
      const double edge = std::arg(hull[(i + 1) % hull.size()] - hull[i]);
      for (const double angle : {-edge, 0.5 * std::numbers::pi - edge}) {
        const double scale = fit_scale(hull, angle, room_w, room_h);
        if (scale > best_scale * (1.0 + 1e-12)) {
          best_scale = scale;
          out.rotation_rad = angle;
        }
      }
    }
  }
  const Point rot = std::polar(1.0, out.rotation_rad);
  double min_x = std::numeric_limits<double>::infinity(), max_x = -min_x;
  double min_y = min_x, max_y = -min_x;
  std::vector<Point> turned(embedding.size());
  for (std::size_t i = 0; i < embedding.size(); ++i) {
    const Point q = rot * embedding[i];
    turned[i] = Point(q.real(), -q.imag());  // mirror: y up → y down
    min_x = std::min(min_x, turned[i].real());
    max_x = std::max(max_x, turned[i].real());
    min_y = std::min(min_y, turned[i].imag());
    max_y = std::max(max_y, turned[i].imag());
  }
  const double extent_x = max_x - min_x;
  const double extent_y = max_y - min_y;
  if (!(extent_x > 0.0 || extent_y > 0.0)) throw NumericalError("the embedding has no extent");
  out.pixels_per_unit = std::min(extent_x > 0.0 ? room_w / extent_x : std::numeric_limits<double>::infinity(),
                                 extent_y > 0.0 ? room_h / extent_y : std::numeric_limits<double>::infinity());
  const Point centre_in(0.5 * (min_x + max_x), 0.5 * (min_y + max_y));
  const Point centre_out(0.5 * options.width, 0.5 * options.height);
  out.pixels.resize(embedding.size());
  for (std::size_t i = 0; i < embedding.size(); ++i) {
    out.pixels[i] = centre_out + out.pixels_per_unit * (turned[i] - centre_in);
  }
  return out;
}

}  // namespace texwarp::mesh
