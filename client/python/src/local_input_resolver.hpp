// LocalInputResolver: a local job's inputs (texwarp.run_local): paths relative to a base folder, inline images
// through a scratch file, no blobs (they live in a texwarpd's store). As the `texwarp run` command resolves them.
#pragma once

#include <filesystem>
#include <string>

#include "texwarp/runner/input_resolver.hpp"

namespace texwarp::python {

class LocalInputResolver final : public runner::InputResolver {
 public:
  LocalInputResolver(std::filesystem::path base, std::filesystem::path scratch);
  std::string image_file(const proto::ImageSourceSpec& image, const proto::JsonPath& json_path) override;
  std::string mesh_file(const proto::MeshSourceSpec& source, const proto::JsonPath& json_path) override;

 private:
  std::string existing(const std::string& path, const proto::JsonPath& json_path) const;

  std::filesystem::path base_;
  std::filesystem::path scratch_;
};

}  // namespace texwarp::python
