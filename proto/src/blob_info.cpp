// BlobInfo JSON: see blob_info.hpp.
#include "texwarp/proto/blob_info_codec.hpp"

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {

nlohmann::json encode_blob_info(const BlobInfo& blob) {
  return {{"id", blob.id}, {"bytes", blob.bytes}, {"created", blob.created}};
}

BlobInfo decode_blob_info(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  BlobInfo b;
  const auto id = r.optional_string("id");
  if (!id) throw InputError(r.key_path("id"), "required key is missing");
  b.id = *id;
  const auto bytes = r.optional_integer("bytes");
  if (!bytes || *bytes < 0) throw InputError(r.key_path("bytes"), "expected a non-negative integer");
  b.bytes = static_cast<std::uint64_t>(*bytes);
  if (auto c = r.optional_bool("created")) b.created = *c;
  return b;
}

}  // namespace texwarp::proto
