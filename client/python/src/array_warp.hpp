// texwarp.warp and texwarp.map_points: a NumPy image or point array in memory warped (or mapped) in this process,
// no files touched; the pixels converted to and from floats as the PNG reader and writer do (png_codec.cpp).
#pragma once

#include <pybind11/pybind11.h>

namespace texwarp::python {

// Adds warp(image, features, *, …) and map_points(points, features, *, …) to the module.
void register_array_functions(pybind11::module_& module);

}  // namespace texwarp::python
