// The colour spaces known by name: see image_role.hpp.
#include "texwarp/proto/image_role.hpp"

#include <cctype>

namespace texwarp::proto {

namespace {

std::string lowercase(std::string_view name) {
  std::string n(name);
  for (char& c : n) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return n;
}

}  // namespace

std::optional<std::string> canonical_color_space(std::string_view name) {
  const std::string n = lowercase(name);
  if (n == "srgb" || n == "srgb_texture" || n == "srgb - texture" || n == "srgb_tx" || n == "gammacorrected2.2") {
    return std::string(kSrgbColorSpace);
  }
  if (is_data_color_space(n) || n == "linear" || n == "lin_srgb" || n == "lin_rec709" || n == "scene_linear" ||
      n == "linear rec.709 (srgb)") {
    return std::string(kLinearColorSpace);
  }
  return std::nullopt;
}

bool is_data_color_space(std::string_view name) {
  const std::string n = lowercase(name);
  return n == "raw" || n == "non-color" || n == "utility - raw";
}

std::string quoted_color_space_names() {
  return std::string("\"") + kSrgbColorSpace + "\" or \"" + kLinearColorSpace + "\"";
}

}  // namespace texwarp::proto
