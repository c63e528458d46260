// EdgeKey: an undirected mesh edge {a, b} packed into one integer, for hash maps keyed by edge.
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>

namespace texwarp::mesh {

using EdgeKey = std::uint64_t;

inline EdgeKey edge_key(int a, int b) {
  const auto lo = static_cast<std::uint32_t>(std::min(a, b));
  const auto hi = static_cast<std::uint32_t>(std::max(a, b));
  return (static_cast<EdgeKey>(lo) << 32) | hi;
}

inline std::pair<int, int> edge_vertices(EdgeKey key) {
  return {static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu)};
}

}  // namespace texwarp::mesh
