// RegionSpec: the part of a mesh to texture as it travels (the region file, the job's "mesh.region"):
// {"faces": [f, ...]} or {"boundary": [v0, v1, ...], "seed_face": f}, 0-based ids.
#pragma once

#include <vector>

#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

struct RegionSpec {
  std::vector<int> faces;     // a face set (each listed once), or
  std::vector<int> boundary;  // a closed vertex curve (consecutive vertices joined by shortest edge paths)
  int seed_face = -1;         // with a face on the side to keep

  bool is_curve() const { return !boundary.empty(); }
  friend TEXWARP_API bool operator==(const RegionSpec&, const RegionSpec&);
};

}  // namespace texwarp::proto
