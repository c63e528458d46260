// The JSON codec of BlobInfo (blob_info.hpp): POST /v1/blobs's answer.
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/proto/blob_info.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

nlohmann::json encode_blob_info(const BlobInfo& blob);
BlobInfo decode_blob_info(const nlohmann::json& value, const JsonPath& path = {});

}  // namespace texwarp::proto
