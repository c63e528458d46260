// Feature naming for messages: see feature.hpp.
#include "texwarp/core/feature.hpp"

namespace texwarp {

std::string describe_feature(const std::vector<Feature>& features, std::size_t index) {
  std::string s = "features[" + std::to_string(index) + "]";
  if (index < features.size() && !features[index].id.empty()) s += " (\"" + features[index].id + "\")";
  return s;
}

}  // namespace texwarp
