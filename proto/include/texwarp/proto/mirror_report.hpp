// The report's "mirror" section (check and image job reports): whether the targets look like a mirror image of
// the sources, and whether the `mirror` option (flip the texture horizontally first) was applied.
#pragma once

#include <optional>
#include <string>

#include "texwarp/proto/export.hpp"

namespace texwarp::proto {

struct MirrorReport {
  bool detected = false;                  // the reflected similarity fits much better (core/mirror.hpp)
  double residual_ratio = 1.0;            // reflected fit's residual / proper fit's
  bool applied = false;                   // the warp ran on the texture flipped horizontally (`mirror`)
  std::optional<std::string> suggestion;  // detected and not applied: what to do
  TEXWARP_API bool operator==(const MirrorReport&) const;
};

}  // namespace texwarp::proto
