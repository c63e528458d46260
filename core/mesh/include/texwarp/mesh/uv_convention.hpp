// UV convention (DESIGN.md §3): u = x / width; v = 1 − y / height for "bottom_left" (OBJ, DCC tools, the
// default) or v = y / height for "top_left" (glTF), x and y in texture pixels (y down).
#pragma once

#include <array>

#include "texwarp/core/point.hpp"
#include "texwarp/proto/output_enums.hpp"

namespace texwarp::mesh {

using proto::UvOrigin;  // names: proto/output_enums.hpp

inline std::array<double, 2> pixel_to_uv(Point px, int width, int height, UvOrigin origin) {
  const double u = px.real() / width;
  const double v = px.imag() / height;
  return {u, origin == UvOrigin::kBottomLeft ? 1.0 - v : v};
}

inline Point uv_to_pixel(std::array<double, 2> uv, int width, int height, UvOrigin origin) {
  const double y = origin == UvOrigin::kBottomLeft ? 1.0 - uv[1] : uv[1];
  return {uv[0] * width, y * height};
}

}  // namespace texwarp::mesh
