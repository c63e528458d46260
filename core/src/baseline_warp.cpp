// Baseline warps (TPS, MLS) on a problem's features: see baseline_warp.hpp.
#include "texwarp/core/baseline_warp.hpp"

#include <memory>
#include <stdexcept>

#include "texwarp/core/image_buffer.hpp"
#include "texwarp/core/moving_least_squares.hpp"
#include "texwarp/core/thin_plate_spline.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp {

WarpMethod parse_warp_method(const std::string& name, const InputLocation& where) {
  if (name == "field") return WarpMethod::kField;
  if (name == "tps") return WarpMethod::kThinPlateSpline;
  if (name == "mls") return WarpMethod::kMovingLeastSquares;
  throw InputError(where, R"(expected "field", "tps" or "mls", got ")" + name + "\"");
}

const char* to_string(WarpMethod method) {
  switch (method) {
    case WarpMethod::kField:
      return "field";
    case WarpMethod::kThinPlateSpline:
      return "tps";
    case WarpMethod::kMovingLeastSquares:
      return "mls";
  }
  return "?";
}

std::function<Point(Point)> baseline_map(WarpMethod method, const WarpProblem& problem, bool inverse) {
  std::vector<Point> from;
  std::vector<Point> to;
  for (const Feature& f : problem.features()) {
    from.push_back(inverse ? f.target : f.source);
    to.push_back(inverse ? f.source : f.target);
  }
  switch (method) {
    case WarpMethod::kThinPlateSpline: {
      if (from.size() < 3) throw InputError(JsonPath{"features"}, "the thin-plate spline needs at least 3 features");
      std::shared_ptr<const ThinPlateSpline> tps;
      try {
        tps = std::make_shared<const ThinPlateSpline>(from, to);
      } catch (const std::invalid_argument&) {
        throw InputError(JsonPath{"features"}, "the thin-plate spline cannot be fitted: the features are collinear");
      }
      return [tps](Point p) { return (*tps)(p); };
    }
    case WarpMethod::kMovingLeastSquares: {
      if (from.size() < 2) throw InputError(JsonPath{"features"}, "moving least squares needs at least 2 features");
      auto mls = std::make_shared<const MovingLeastSquares>(from, to);
      return [mls](Point p) { return (*mls)(p); };
    }
    case WarpMethod::kField:
      break;
  }
  throw std::invalid_argument("baseline_map: not a baseline method");
}

std::vector<Point> baseline_inverse_map_grid(WarpMethod method, const WarpProblem& problem, int width, int height) {
  const auto map = baseline_map(method, problem, true);
  std::vector<Point> grid = huge_page_vector<Point>(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) grid[static_cast<std::size_t>(y) * width + x] = map(Point(x + 0.5, y + 0.5));
  }
  return grid;
}

}  // namespace texwarp
