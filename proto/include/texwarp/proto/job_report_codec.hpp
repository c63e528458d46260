// JSON codec of the typed report (job_report.hpp; schema: proto/schema/report.schema.json). Encoding writes the
// report files' exact keys; decoding is lenient like every response codec (unknown keys are ignored) but requires
// every key the schema requires, InputError naming its JSON path. Numbers that are not finite are null in JSON.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/proto/job_report.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

nlohmann::json encode_job_report(const JobReport& report);
JobReport decode_job_report(const nlohmann::json& value, const JsonPath& path = {});

nlohmann::json encode_check_report(const CheckReport& report);
CheckReport decode_check_report(const nlohmann::json& value, const JsonPath& path = {});

nlohmann::json encode_mesh_mapping_report(const MeshMappingReport& report);
MeshMappingReport decode_mesh_mapping_report(const nlohmann::json& value, const JsonPath& path = {});

nlohmann::json encode_certificate_report(const CertificateReport& report);
CertificateReport decode_certificate_report(const nlohmann::json& value, const JsonPath& path = {});

const char* to_string(JacobianEstimate map);
const char* to_string(WarpMethodReport method);

}  // namespace texwarp::proto
