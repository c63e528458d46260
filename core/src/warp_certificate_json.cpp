// The warp certificate in the typed report: see warp_certificate_json.hpp.
#include "texwarp/core/warp_certificate_json.hpp"

#include "texwarp/proto/job_report_codec.hpp"

namespace texwarp {

proto::CertificateReport certificate_report(const WarpCertificate& c) {
  proto::CertificateReport r;
  r.exact = c.exact;
  r.tolerance_px = c.tolerance_px;
  r.max_error_px_estimated = c.max_error_px_estimated;
  r.max_error_px_sampled = c.max_error_px_sampled;
  r.max_error_px_bound = c.max_error_px_bound;
  r.sampled_pixels = c.sampled_pixels;
  r.min_jacobian_det = c.min_jacobian_det;
  r.nonpositive_jacobians = c.nonpositive_jacobians;
  r.pathlines = c.pathlines;
  r.jacobian_pathlines = c.jacobian_pathlines;
  r.cells = c.cells;
  r.pixel_pathlines = c.pixel_pathlines;
  r.smallest_cell_px = c.smallest_cell_px;
  return r;
}

}  // namespace texwarp
