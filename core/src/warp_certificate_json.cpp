// The warp certificate as JSON: see warp_certificate_json.hpp.
#include "texwarp/core/warp_certificate_json.hpp"

namespace texwarp {

nlohmann::json to_json(const WarpCertificate& c) {
  return {{"exact", c.exact},
          {"tolerance_px", c.tolerance_px},
          {"max_error_px_estimated", c.max_error_px_estimated},
          {"max_error_px_sampled", c.max_error_px_sampled},
          {"sampled_pixels", c.sampled_pixels},
          {"min_jacobian_det", c.min_jacobian_det},
          {"nonpositive_jacobians", c.nonpositive_jacobians},
          {"pathlines", c.pathlines},
          {"jacobian_pathlines", c.jacobian_pathlines},
          {"cells", c.cells},
          {"smallest_cell_px", c.smallest_cell_px}};
}

}  // namespace texwarp
