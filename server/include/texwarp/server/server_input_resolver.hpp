// ServerInputResolver: a job's inputs as the server may read them: blob ids from its blob store, paths only under
// the configured input roots (checked lexically and again after symlinks are resolved), never the server's own
// layout in a message.
#pragma once

#include <filesystem>
#include <vector>

#include "texwarp/runner/input_resolver.hpp"
#include "texwarp/server/blob_store.hpp"

namespace texwarp::server {

class ServerInputResolver final : public runner::InputResolver {
 public:
  ServerInputResolver(BlobStore& blobs, std::vector<std::filesystem::path> roots)
      : blobs_(blobs), roots_(std::move(roots)) {}

  std::string image_file(const proto::ImageSourceSpec& image, const proto::JsonPath& json_path) override;
  std::string mesh_file(const proto::MeshSourceSpec& source, const proto::JsonPath& json_path) override;

 private:
  std::string blob_file(const std::string& id, const proto::JsonPath& json_path);
  std::string rooted_file(const std::string& path, const proto::JsonPath& json_path);

  BlobStore& blobs_;
  std::vector<std::filesystem::path> roots_;  // canonical
};

}  // namespace texwarp::server
