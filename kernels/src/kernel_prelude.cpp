// The pathline program's #define prelude from the contract table: see kernel_prelude.hpp.
#include "kernel_prelude.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace texwarp::kernels_detail {
namespace {

// The shortest decimal that reads back as `value` in the kernel's real type, always a floating literal.
std::string real_literal(double value, bool double_precision) {
  if (!std::isfinite(value)) throw std::logic_error("kernel constants are finite");
  char text[64];
  const std::to_chars_result r = double_precision ? std::to_chars(text, text + sizeof text, value)
                                                  : std::to_chars(text, text + sizeof text, static_cast<float>(value));
  if (r.ec != std::errc()) throw std::logic_error("kernel constant does not format");
  std::string out(text, r.ptr);
  if (out.find_first_of(".e") == std::string::npos) out += ".0";
  if (!double_precision) out += 'f';
  return out;
}

}  // namespace

std::string kernel_literal(const KernelConstant& constant, bool double_precision) {
  const double value = double_precision ? constant.double_value : constant.float_value;
  switch (constant.kind) {
    case KernelConstant::Kind::kInt:
      return std::to_string(static_cast<long long>(value));
    case KernelConstant::Kind::kReal:
      return "(" + real_literal(value, double_precision) + ")";
    case KernelConstant::Kind::kRealArray: {
      const std::size_t row = constant.row == 0 ? constant.values.size() : constant.row;
      const bool nested = constant.row != 0;
      std::string out = "{";
      for (std::size_t i = 0; i < constant.values.size(); ++i) {
        if (i > 0) out += ", ";
        if (nested && i % row == 0) out += "{";
        out += real_literal(constant.values[i], double_precision);
        if (nested && i % row == row - 1) out += "}";
      }
      return out + "}";
    }
  }
  throw std::logic_error("unknown kernel constant kind");
}

std::string kernel_prelude(KernelVariant variant) {
  std::string out = "// The host-kernel contract (kernels/src/kernel_contract.hpp), emitted by kernel_prelude().\n";
  if (variant.double_precision) out += "#define TW_DOUBLE\n";
  if (variant.jacobian) out += "#define TW_JACOBIAN\n";
  for (const KernelConstant& c : kKernelConstants) {
    out += "#define ";
    out += c.name;
    out += ' ';
    out += kernel_literal(c, variant.double_precision);
    out += '\n';
  }
  return out;
}

}  // namespace texwarp::kernels_detail
