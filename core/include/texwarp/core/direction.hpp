// Direction: which way a flow runs its pathlines, forward (t = 0 → 1, the map W) or inverse (t = 1 → 0, W⁻¹).
#pragma once

namespace texwarp {

enum class Direction { kForward, kInverse };

}  // namespace texwarp
