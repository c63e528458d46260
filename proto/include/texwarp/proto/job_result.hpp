// JobResult: what GET /v1/jobs/{id}/result lists for a succeeded job: its files (name, media type, size,
// SHA-256, where to GET it) and the report (residuals, quality metrics, certificate, timings).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "texwarp/proto/job_spec.hpp"

namespace texwarp::proto {

struct ResultFile {
  std::string name;        // "warped.png", "mesh.obj", "uvs.json", "report.json"
  std::string media_type;  // "image/png", "model/obj", "application/json", ...
  std::uint64_t bytes = 0;
  std::string sha256;             // lowercase hex of the file's bytes
  std::string href;               // "/v1/jobs/{id}/files/{name}"
  std::optional<ImageRole> role;  // a warped image: the role its map was sampled with; absent for other files
};

struct JobResult {
  std::string job_id;
  JobKind kind = JobKind::kImage;
  std::vector<ResultFile> files;
  std::string report_json = "{}";  // the report: the same JSON object as the report.json file (compact text)
};

}  // namespace texwarp::proto
