// The baselines beside the vector-field method, for the side-by-side of the paper's Fig. 2: thin-plate spline
// and similarity moving least squares fitted on the same features (positions only; frames are ignored).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "texwarp/core/point.hpp"
#include "texwarp/core/warp_problem.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp {

enum class WarpMethod { kField, kThinPlateSpline, kMovingLeastSquares };

// "field" | "tps" | "mls"; InputError at `where` (the option that gave it) otherwise.
WarpMethod parse_warp_method(const std::string& name, const proto::InputLocation& where);
const char* to_string(WarpMethod method);

// A baseline's map for the problem's features: forward (source → target pixels) or inverse (target → source),
// each fitted directly in its direction (neither baseline has a closed-form inverse). kField is not a baseline.
std::function<Point(Point)> baseline_map(WarpMethod method, const WarpProblem& problem, bool inverse);

// The inverse map at every output pixel centre, row-major.
std::vector<Point> baseline_inverse_map_grid(WarpMethod method, const WarpProblem& problem, int width, int height);

}  // namespace texwarp
