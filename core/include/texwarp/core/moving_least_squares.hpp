// MovingLeastSquares: the similarity moving-least-squares deformation (Schaefer, McPhail & Warren 2006), a
// baseline: at each point the similarity that best maps the features, weighted by 1/|p_i − v|^(2α).
#pragma once

#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp {

class MovingLeastSquares {
 public:
  // f(src_k) = dst_k exactly; alpha is the paper's weight exponent (1 by default there).
  MovingLeastSquares(std::vector<Point> src, std::vector<Point> dst, double alpha = 1.0);

  Point operator()(Point v) const;

 private:
  std::vector<Point> src_;
  std::vector<Point> dst_;
  double alpha_;
};

}  // namespace texwarp
