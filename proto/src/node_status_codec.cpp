// JSON codec for nodes: see node_status_codec.hpp.
#include "texwarp/proto/node_status_codec.hpp"

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {
namespace {

std::string required_string(JsonReader& r, std::string_view key) {
  const auto v = r.optional_string(key);
  if (!v) throw InputError(r.key_path(key), "required key is missing");
  return *v;
}

int count(JsonReader& r, std::string_view key) {
  const auto v = r.optional_integer(key);
  if (!v) return 0;
  if (*v < 0 || *v > 1'000'000) throw InputError(r.key_path(key), "expected a count from 0 to 1000000");
  return static_cast<int>(*v);
}

}  // namespace

nlohmann::json encode_node_status(const NodeStatus& n) {
  return {{"id", n.id},          {"address", n.address},       {"version", n.version},           {"workers", n.workers},
          {"pid", n.pid},        {"started_at", n.started_at}, {"last_seen_at", n.last_seen_at}, {"alive", n.alive},
          {"running", n.running}};
}

NodeStatus decode_node_status(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  NodeStatus n;
  n.id = required_string(r, "id");
  if (auto v = r.optional_string("address")) n.address = *v;
  if (auto v = r.optional_string("version")) n.version = *v;
  n.workers = count(r, "workers");
  if (auto v = r.optional_integer("pid")) n.pid = *v;
  if (auto v = r.optional_string("started_at")) n.started_at = *v;
  if (auto v = r.optional_string("last_seen_at")) n.last_seen_at = *v;
  if (auto v = r.optional_bool("alive")) n.alive = *v;
  n.running = count(r, "running");
  return n;
}

nlohmann::json encode_node_list(const NodeList& list) {
  nlohmann::json nodes = nlohmann::json::array();
  for (const auto& n : list.nodes) nodes.push_back(encode_node_status(n));
  return {{"nodes", std::move(nodes)}};
}

NodeList decode_node_list(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  NodeList list;
  const auto& nodes = r.at("nodes");
  if (!nodes.is_array()) throw InputError(r.key_path("nodes"), "expected an array, got " + json_type_name(nodes));
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    list.nodes.push_back(decode_node_status(nodes[i], r.key_path("nodes").index(i)));
  }
  return list;
}

}  // namespace texwarp::proto
