// BlobInfo: what POST /v1/blobs answers: the content address of the uploaded bytes and their size; `created`
// is false when the server already held the same bytes (uploads are deduplicated). With its JSON codec.
#pragma once

#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

struct BlobInfo {
  std::string id;  // "sha256:<64 hex>": use as {"image": {"blob": id}} in a job
  std::uint64_t bytes = 0;
  bool created = false;
};

nlohmann::json encode_blob_info(const BlobInfo& blob);
BlobInfo decode_blob_info(const nlohmann::json& value, const JsonPath& path = {});

}  // namespace texwarp::proto
