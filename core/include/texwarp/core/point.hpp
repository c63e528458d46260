// Point: a 2D point or vector as a complex number z = x + i·y (DESIGN.md §1), in pixel units.
#pragma once

#include <complex>

namespace texwarp {

using Point = std::complex<double>;

}  // namespace texwarp
