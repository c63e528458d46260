// UV origin names: see uv_convention.hpp.
#include "texwarp/mesh/uv_convention.hpp"

#include "texwarp/proto/input_error.hpp"

namespace texwarp::mesh {

UvOrigin parse_uv_origin(const std::string& name) {
  if (name == "bottom_left") return UvOrigin::kBottomLeft;
  if (name == "top_left") return UvOrigin::kTopLeft;
  throw InputError("uv_origin", "expected \"bottom_left\" or \"top_left\", got \"" + name + "\"");
}

const char* to_string(UvOrigin origin) { return origin == UvOrigin::kBottomLeft ? "bottom_left" : "top_left"; }

}  // namespace texwarp::mesh
