// The #define prelude of the pathline program: kernel_contract.hpp's table written as OpenCL C for one variant
// (precision, Jacobian), prepended to kernels/cl/*.cl when the program is built.
#pragma once

#include <compare>
#include <string>

#include "kernel_contract.hpp"

namespace texwarp::kernels_detail {

// Which pathline program: float or double arithmetic (TW_DOUBLE), with the variational equation (TW_JACOBIAN).
struct KernelVariant {
  bool double_precision = false;
  bool jacobian = false;
  auto operator<=>(const KernelVariant&) const = default;
};

// A value as the variant's kernel reads it: integers in decimal; reals in the shortest form that reads back to
// the same float (with an f suffix) or double; arrays as initializer lists of those.
std::string kernel_literal(const KernelConstant& constant, bool double_precision);

// "#define NAME literal" for every entry of kKernelConstants, in table order, after TW_DOUBLE / TW_JACOBIAN when
// the variant asks for them; one line each.
std::string kernel_prelude(KernelVariant variant);

}  // namespace texwarp::kernels_detail
