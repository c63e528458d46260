// UDIM tiles on the wire: a path holding the token <UDIM> names the tiles 1001–1100 that exist; tile
// 1001 + u + 10·v is column u, row v counting upward in UV space.
#pragma once

namespace texwarp::proto {

inline constexpr const char* kUdimToken = "<UDIM>";
inline constexpr int kFirstUdimTile = 1001;
inline constexpr int kLastUdimTile = 1100;
inline constexpr int kUdimColumns = 10;  // u = (tile − 1001) mod 10, v = (tile − 1001) div 10

}  // namespace texwarp::proto
