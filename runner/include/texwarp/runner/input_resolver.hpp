// InputResolver: how a job's inputs become files the pipeline can read. The server maps blob ids to its blob
// store and allows paths only under configured roots; `texwarp run` reads paths relative to the job file.
#pragma once

#include <string>

#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::runner {

class InputResolver {
 public:
  virtual ~InputResolver() = default;

  // A readable file holding the job's image. InputError at `json_path` ("$.image") when the blob is unknown, the
  // path is not allowed or missing. Messages never show the server's own file layout.
  virtual std::string image_file(const proto::ImageSourceSpec& image, const proto::JsonPath& json_path) = 0;

  // A readable file holding a blob or path mesh source (kBlob, kPath), as for image_file.
  virtual std::string mesh_file(const proto::MeshSourceSpec& source, const proto::JsonPath& json_path) = 0;
};

}  // namespace texwarp::runner
