// The warp certificate as a section of the typed report (proto/job_report.hpp), and as JSON (the CLI's
// --certificate file and the "certificate" of a job's report).
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/core/certified_warp.hpp"
#include "texwarp/proto/job_report.hpp"

namespace texwarp {

proto::CertificateReport certificate_report(const WarpCertificate& certificate);

// encode_certificate_report(certificate_report(certificate)): the keys of proto::CertificateReport.
nlohmann::json to_json(const WarpCertificate& certificate);

}  // namespace texwarp
