// ScratchResolver: a runner::InputResolver for tests that run jobs in-process: an inline (base64) texture goes
// through a file in a scratch folder; mesh files are refused at the job's JSON path.
#pragma once

#include <filesystem>
#include <string>
#include <utility>

#include "texwarp/core/text_file.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/runner/input_resolver.hpp"

namespace texwarp::testing {

class ScratchResolver final : public runner::InputResolver {
 public:
  explicit ScratchResolver(std::filesystem::path dir) : dir_(std::move(dir)) {}
  std::string image_file(const proto::ImageSourceSpec& image, const proto::JsonPath&) override {
    const std::filesystem::path file = dir_ / "texture";
    write_text_file_atomically(file.string(), image.data);
    return file.string();
  }
  std::string mesh_file(const proto::MeshSourceSpec&, const proto::JsonPath& path) override {
    throw InputError(path, "no mesh files here");
  }

 private:
  std::filesystem::path dir_;
};

}  // namespace texwarp::testing
