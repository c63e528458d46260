// The warp certificate as a section of the typed report (proto/job_report.hpp): the CLI's --certificate file and
// the "certificate" of a job's report, encoded by proto's codec.
#pragma once

#include "texwarp/core/certified_warp.hpp"
#include "texwarp/proto/job_report.hpp"

namespace texwarp {

proto::CertificateReport certificate_report(const WarpCertificate& certificate);

}  // namespace texwarp
