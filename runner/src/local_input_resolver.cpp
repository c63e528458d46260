// LocalInputResolver: see local_input_resolver.hpp.
#include "texwarp/runner/local_input_resolver.hpp"

#include <cctype>
#include <cstdio>
#include <functional>

#include "texwarp/core/text_file.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::runner {

namespace fs = std::filesystem;

LocalInputResolver::LocalInputResolver(fs::path base, fs::path scratch)
    : base_(std::move(base)), scratch_(std::move(scratch)) {}

std::string LocalInputResolver::image_file(const proto::ImageSourceSpec& image, const proto::JsonPath& json_path) {
  switch (image.kind) {
    case proto::ImageSourceSpec::Kind::kPath:
      return existing(image.path, json_path.key("path"));
    case proto::ImageSourceSpec::Kind::kBase64: {
      // One file per place in the job and content: a texture set's inline maps (and a UDIM texture's tiles) each
      // have their own, and another job run with the same scratch folder never reads an earlier one's bytes.
      std::string name = "inline-image";
      if (json_path.str() != "$.image") {
        for (const char c : json_path.str()) name += std::isalnum(static_cast<unsigned char>(c)) ? c : '-';
      }
      char digest[17];
      std::snprintf(digest, sizeof digest, "%016zx", std::hash<std::string>{}(image.data));
      name += std::string("-") + digest;
      const fs::path file = scratch_ / name;
      if (!fs::exists(file)) write_text_file_atomically(file.string(), image.data);
      return file.string();
    }
    case proto::ImageSourceSpec::Kind::kBlob:
      break;
    case proto::ImageSourceSpec::Kind::kTiles:
      throw InputError(json_path.key("tiles"), "a UDIM texture's tiles are files one by one, not one file");
  }
  throw InputError(json_path.key("blob"),
                   "a blob id names a file in a texwarpd's store; a local run (`texwarp run`, run_local) needs the "
                   "image by \"path\" or inline (\"base64\")");
}

std::string LocalInputResolver::mesh_file(const proto::MeshSourceSpec& source, const proto::JsonPath& json_path) {
  if (source.kind == proto::MeshSourceSpec::Kind::kPath) return existing(source.path, json_path.key("path"));
  throw InputError(json_path.key("blob"),
                   "a blob id names a file in a texwarpd's store; a local run (`texwarp run`, run_local) needs the "
                   "mesh by \"path\" or inline");
}

std::string LocalInputResolver::existing(const std::string& path, const proto::JsonPath& json_path) const {
  const fs::path p = fs::path(path).is_absolute() ? fs::path(path) : base_ / path;
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) throw InputError(json_path, "no such file: " + p.string());
  return p.string();
}

}  // namespace texwarp::runner
