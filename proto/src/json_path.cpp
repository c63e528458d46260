// JSON paths: see json_path.hpp.
#include "texwarp/proto/json_path.hpp"

#include "texwarp/proto/utf8_text.hpp"

namespace texwarp::proto {

JsonPath::JsonPath(std::initializer_list<std::string_view> keys) {
  for (const std::string_view k : keys) steps_.emplace_back(std::string(k));
}

JsonPath JsonPath::key(std::string_view key) const {
  JsonPath child = *this;
  child.steps_.emplace_back(key.size() > kMaxKeyShown ? utf8_prefix(key, kMaxKeyShown) : std::string(key));
  return child;
}

JsonPath JsonPath::index(std::size_t index) const {
  JsonPath child = *this;
  child.steps_.emplace_back(index);
  return child;
}

JsonPath JsonPath::rebased(const JsonPath& base) const {
  JsonPath placed = base;
  placed.steps_.insert(placed.steps_.end(), steps_.begin(), steps_.end());
  return placed;
}

std::string JsonPath::str() const {
  std::string out = "$";
  for (const auto& step : steps_) {
    if (const auto* k = std::get_if<std::string>(&step)) {
      out += "." + *k;
    } else {
      out += "[" + std::to_string(std::get<std::size_t>(step)) + "]";
    }
  }
  return out;
}

}  // namespace texwarp::proto
