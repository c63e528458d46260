// ScratchResolver: a runner::InputResolver for tests that run jobs in-process: an inline (base64) texture goes
// through a file in a scratch folder (one per place in the job); mesh files are refused at the job's JSON path.
#pragma once

#include <cctype>
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
  std::string image_file(const proto::ImageSourceSpec& image, const proto::JsonPath& path) override {
    // One file per place in the job: a texture set's maps each have their own.
    std::string name = "texture";
    if (path.str() != "$.image") {
      for (const char c : path.str()) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
    }
    const std::filesystem::path file = dir_ / name;
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
