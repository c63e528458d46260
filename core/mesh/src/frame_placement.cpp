// Placement of an embedding into the texture frame: see frame_placement.hpp.
#include "texwarp/mesh/frame_placement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "texwarp/core/numerical_error.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {

FramePlacement place_in_frame(std::span<const Point> embedding, const FramePlacementOptions& options) {
  if (options.width <= 0 || options.height <= 0) {
    throw InputError("frame", "the texture frame must have a positive size, got " + std::to_string(options.width) +
                                  "×" + std::to_string(options.height));
  }
  const double room_w = options.width - 2.0 * options.margin_px;
  const double room_h = options.height - 2.0 * options.margin_px;
  if (!(options.margin_px >= 0.0) || room_w <= 0.0 || room_h <= 0.0) {
    throw InputError("margin", "a margin of " + std::to_string(options.margin_px) + " px leaves no room in a " +
                                   std::to_string(options.width) + "×" + std::to_string(options.height) + " frame");
  }
  FramePlacement out;
  if (options.align_principal_axis && !embedding.empty()) {
    // Principal axis of the vertex cloud: half the argument of Σ (p − mean)².
    Point mean(0.0, 0.0);
    for (Point p : embedding) mean += p;
    mean /= static_cast<double>(embedding.size());
    Point second(0.0, 0.0);
    for (Point p : embedding) second += (p - mean) * (p - mean);
    const double axis = 0.5 * std::arg(second);
    const double target = options.width >= options.height ? 0.0 : 0.5 * std::acos(-1.0);
    out.rotation_rad = std::abs(second) > 0.0 ? target - axis : 0.0;
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
