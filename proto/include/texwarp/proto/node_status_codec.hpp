// JSON codec for NodeStatus and NodeList (schema: proto/schema/node-list.schema.json). Responses are decoded
// leniently (a newer server may add keys).
#pragma once

#include <nlohmann/json.hpp>

#include "texwarp/proto/json_path.hpp"
#include "texwarp/proto/node_status.hpp"

namespace texwarp::proto {

nlohmann::json encode_node_status(const NodeStatus& node);
NodeStatus decode_node_status(const nlohmann::json& value, const JsonPath& path = {});

nlohmann::json encode_node_list(const NodeList& list);
NodeList decode_node_list(const nlohmann::json& value, const JsonPath& path = {});

}  // namespace texwarp::proto
