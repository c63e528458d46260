// Job inputs on the server: see server_input_resolver.hpp.
#include "texwarp/server/server_input_resolver.hpp"

#include <algorithm>

#include "texwarp/proto/input_error.hpp"

namespace texwarp::server {
namespace {

namespace fs = std::filesystem;

bool is_under(const fs::path& path, const fs::path& root) {
  auto p = path.begin();
  for (auto r = root.begin(); r != root.end(); ++r, ++p) {
    if (r->empty()) continue;  // a trailing separator
    if (p == path.end() || *p != *r) return false;
  }
  return true;
}

}  // namespace

std::string ServerInputResolver::blob_file(const std::string& id, const proto::JsonPath& json_path) {
  if (!blobs_.contains(id)) {
    throw InputError(json_path, "no blob " + id + " on this server: upload the file first (POST /v1/blobs)");
  }
  return blobs_.path_of(id).string();
}

std::string ServerInputResolver::rooted_file(const std::string& path, const proto::JsonPath& json_path) {
  if (roots_.empty()) {
    throw InputError(json_path, "this server reads no files by path (it has no --input-root): upload the file "
                                "(POST /v1/blobs) or send it inline");
  }
  const fs::path given(path);
  if (!given.is_absolute()) throw InputError(json_path, "expected an absolute path");
  const fs::path lexical = given.lexically_normal();
  const auto allowed = [&](const fs::path& p) {
    return std::any_of(roots_.begin(), roots_.end(), [&](const fs::path& root) { return is_under(p, root); });
  };
  if (!allowed(lexical)) throw InputError(json_path, "not under an input root of this server");
  std::error_code ec;
  const fs::path real = fs::canonical(lexical, ec);
  if (ec) throw InputError(json_path, "no such file under the input roots");
  if (!allowed(real)) throw InputError(json_path, "resolves (through a symbolic link) outside the input roots");
  if (!fs::is_regular_file(real, ec)) throw InputError(json_path, "not a regular file");
  return real.string();
}

std::string ServerInputResolver::image_file(const proto::ImageSourceSpec& image, const proto::JsonPath& json_path) {
  switch (image.kind) {
    case proto::ImageSourceSpec::Kind::kBlob:
      return blob_file(image.blob, json_path.key("blob"));
    case proto::ImageSourceSpec::Kind::kPath:
      return rooted_file(image.path, json_path.key("path"));
    case proto::ImageSourceSpec::Kind::kBase64:
      return blobs_.path_of(blobs_.put(image.data).id).string();
    case proto::ImageSourceSpec::Kind::kTiles:
      throw InputError(json_path.key("tiles"), "a UDIM texture's tiles are files one by one, not one file");
  }
  throw InputError(json_path, "unknown image source");
}

std::string ServerInputResolver::mesh_file(const proto::MeshSourceSpec& source, const proto::JsonPath& json_path) {
  if (source.kind == proto::MeshSourceSpec::Kind::kBlob) return blob_file(source.blob, json_path.key("blob"));
  if (source.kind == proto::MeshSourceSpec::Kind::kPath) return rooted_file(source.path, json_path.key("path"));
  throw InputError(json_path, "the mesh is inline, not in a file");
}

}  // namespace texwarp::server
