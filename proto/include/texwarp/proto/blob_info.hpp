// BlobInfo: what POST /v1/blobs answers: the content address of the uploaded bytes and their size; `created`
// is false when the server already held the same bytes (uploads are deduplicated). JSON codec:
// blob_info_codec.hpp.
#pragma once

#include <cstdint>
#include <string>

namespace texwarp::proto {

struct BlobInfo {
  std::string id;  // "sha256:<64 hex>": use as {"image": {"blob": id}} in a job
  std::uint64_t bytes = 0;
  bool created = false;
};

}  // namespace texwarp::proto
