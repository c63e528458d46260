// JsonPath: a place in a JSON document ("$.warp.features[3].source"), built by key and index appends; a
// sub-document's path is placed inside the document that holds it with rebased().
#pragma once

#include <cstddef>
#include <initializer_list>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

// Longest user-given key (bytes) kept in a path (and quoted in a message); longer ones are cut between
// characters, with "…" appended.
inline constexpr std::size_t kMaxKeyShown = 64;

class TEXWARP_API JsonPath {
 public:
  JsonPath() = default;  // the document's root, "$"
  // The path of keys from the root: JsonPath{"options", "device"} is "$.options.device".
  JsonPath(std::initializer_list<std::string_view> keys);

  JsonPath key(std::string_view key) const;  // this + ".key" (a key longer than kMaxKeyShown bytes is cut)
  JsonPath index(std::size_t index) const;   // this + "[index]"
  // This path (relative to a sub-document) placed under `base`, the sub-document's path in its document.
  JsonPath rebased(const JsonPath& base) const;

  bool is_root() const { return steps_.empty(); }
  std::string str() const;  // "$", "$.a.b[3]"

  friend TEXWARP_API bool operator==(const JsonPath&, const JsonPath&);

 private:
  std::vector<std::variant<std::string, std::size_t>> steps_;  // a key or an index
};

}  // namespace texwarp::proto
