// LocalInputResolver: the inputs of a job run without a server (`texwarp run`, the Python module's run_local):
// paths relative to a base folder (the job file's), inline images through a scratch file, no blobs (they live in
// a texwarpd's store).
#pragma once

#include <filesystem>
#include <string>

#include "texwarp/runner/input_resolver.hpp"

namespace texwarp::runner {

class LocalInputResolver final : public InputResolver {
 public:
  // `base`: the folder relative paths start from; `scratch`: an existing folder for an inline image's file.
  LocalInputResolver(std::filesystem::path base, std::filesystem::path scratch);
  std::string image_file(const proto::ImageSourceSpec& image, const proto::JsonPath& json_path) override;
  std::string mesh_file(const proto::MeshSourceSpec& source, const proto::JsonPath& json_path) override;

 private:
  std::string existing(const std::string& path, const proto::JsonPath& json_path) const;

  std::filesystem::path base_;
  std::filesystem::path scratch_;
};

}  // namespace texwarp::runner
