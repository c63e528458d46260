// The OpenCL C source of the pathline program (kernels/cl/*.cl), embedded into the library at build time.
#pragma once

#include <string_view>

namespace texwarp::kernels_detail {

// velocity_field.cl followed by pathline.cl, each after a #line directive naming it.
std::string_view pathline_program_source();

}  // namespace texwarp::kernels_detail
