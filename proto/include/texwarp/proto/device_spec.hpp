// DeviceSpec: the compute device a job asks for, "cpu" or "opencl[:<device name substring>]". The grammar is
// parsed here only; jobs, texwarpd's --device, the runner's backend cache and the CLI all use this type.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "texwarp/proto/export.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp::proto {

struct TEXWARP_API DeviceSpec {
  enum class Kind { kCpu, kOpenCl };
  Kind kind = Kind::kCpu;
  std::string name;  // kOpenCl: a device name substring (or cpu|gpu|accelerator); empty: PoCL's default device

  static DeviceSpec cpu() { return {}; }
  static DeviceSpec opencl(std::string name = {}) { return {Kind::kOpenCl, std::move(name)}; }

  std::string str() const;  // "cpu", "opencl" or "opencl:<name>"
  friend TEXWARP_API bool operator==(const DeviceSpec&, const DeviceSpec&);
};

// The device `text` names ("cpu", "opencl", "opencl:<non-empty name>"), or none.
TEXWARP_API std::optional<DeviceSpec> device_from_string(std::string_view text);
// As device_from_string; InputError at `where` for any other text.
TEXWARP_API DeviceSpec parse_device(std::string_view text, const InputLocation& where);

}  // namespace texwarp::proto
