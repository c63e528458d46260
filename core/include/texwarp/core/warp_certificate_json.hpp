// The warp certificate as JSON (the CLI's --certificate file and the service's result report).
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/core/certified_warp.hpp"

namespace texwarp {

// Keys: exact, tolerance_px, max_error_px_estimated, max_error_px_sampled, sampled_pixels, min_jacobian_det,
// nonpositive_jacobians, pathlines, jacobian_pathlines, cells, smallest_cell_px.
nlohmann::json to_json(const WarpCertificate& certificate);

}  // namespace texwarp
