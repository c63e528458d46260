// problem+json encoding and lenient decoding: see problem_details.hpp.
#include "texwarp/proto/problem_details_codec.hpp"

#include "texwarp/proto/json_reader.hpp"

namespace texwarp::proto {

nlohmann::json encode_problem(const ProblemDetails& problem) {
  nlohmann::json j = {{"type", problem.type}, {"title", problem.title}};
  if (problem.status != 0) j["status"] = problem.status;
  if (!problem.detail.empty()) j["detail"] = problem.detail;
  if (!problem.instance.empty()) j["instance"] = problem.instance;
  if (!problem.path.empty()) j["path"] = problem.path;
  return j;
}

ProblemDetails decode_problem(const nlohmann::json& value, const JsonPath& path) {
  JsonReader r(value, path);
  ProblemDetails p;
  if (auto v = r.optional_string("type")) p.type = *v;
  if (auto v = r.optional_string("title")) p.title = *v;
  if (auto v = r.optional_integer("status")) p.status = static_cast<int>(*v);
  if (auto v = r.optional_string("detail")) p.detail = *v;
  if (auto v = r.optional_string("instance")) p.instance = *v;
  if (auto v = r.optional_string("path")) p.path = *v;
  return p;
}

}  // namespace texwarp::proto
