// The device grammar: see device_spec.hpp.
#include "texwarp/proto/device_spec.hpp"

#include "texwarp/proto/input_error.hpp"

namespace texwarp::proto {
namespace {

constexpr std::string_view kCpu = "cpu";
constexpr std::string_view kOpenCl = "opencl";
constexpr std::string_view kOpenClNamed = "opencl:";

}  // namespace

std::string DeviceSpec::str() const {
  if (kind == Kind::kCpu) return std::string(kCpu);
  return name.empty() ? std::string(kOpenCl) : std::string(kOpenClNamed) + name;
}

std::optional<DeviceSpec> device_from_string(std::string_view text) {
  if (text == kCpu) return DeviceSpec::cpu();
  if (text == kOpenCl) return DeviceSpec::opencl();
  if (text.size() > kOpenClNamed.size() && text.substr(0, kOpenClNamed.size()) == kOpenClNamed) {
    return DeviceSpec::opencl(std::string(text.substr(kOpenClNamed.size())));
  }
  return std::nullopt;
}

DeviceSpec parse_device(std::string_view text, const InputLocation& where) {
  if (auto device = device_from_string(text)) return *device;
  throw InputError(where, R"(expected "cpu", "opencl" or "opencl:<device name>", got ")" +
                              std::string(text.substr(0, 80)) + "\"");
}

}  // namespace texwarp::proto
