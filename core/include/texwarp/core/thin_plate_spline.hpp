// ThinPlateSpline: the interpolating thin-plate spline warp (Bookstein 1989), the baseline users reach for.
// It interpolates the features exactly but may fold over; used to show the difference (paper Fig. 2).
#pragma once

#include <vector>

#include "texwarp/core/point.hpp"

namespace texwarp {

class ThinPlateSpline {
 public:
  // f(src_k) = dst_k, minimising bending energy; needs ≥ 3 points not all on a line.
  ThinPlateSpline(const std::vector<Point>& src, const std::vector<Point>& dst);

  Point operator()(Point p) const;

 private:
  Point origin_;                // the sources' centroid
  double scale_ = 1.0;          // 1 / their RMS distance from it: the spline works in these units
  std::vector<Point> centres_;  // sources, normalised
  std::vector<Point> weights_;  // radial weights, complex (x, y components)
  Point affine_[3];             // a0 + a1·x + a2·y per component
};

}  // namespace texwarp
