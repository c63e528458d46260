// Row encodings shared by the job stores: see job_store_rows.hpp.
#include "job_store_rows.hpp"

#include <stdexcept>

#include <nlohmann/json.hpp>

#include "texwarp/proto/enum_names.hpp"
#include "texwarp/proto/problem_details_codec.hpp"
#include "texwarp/server/problem_types.hpp"

namespace texwarp::server::store_rows {

std::string encode_labels(const Labels& labels) {
  nlohmann::json object = nlohmann::json::object();
  for (const auto& [key, value] : labels) object[key] = value;
  return object.dump();
}

Labels decode_labels(const std::string& json, const std::string& where) {
  const auto parsed = nlohmann::json::parse(json, nullptr, /*allow_exceptions=*/false);
  if (!parsed.is_object()) throw std::runtime_error(where + ": not a JSON object of labels: " + json.substr(0, 80));
  Labels labels;
  for (const auto& [key, value] : parsed.items()) {
    if (!value.is_string()) throw std::runtime_error(where + ": label \"" + key.substr(0, 63) + "\" is not a string");
    labels.emplace(key, value.get<std::string>());
  }
  return labels;
}

proto::JobState decode_state(const std::string& text, const std::string& where) {
  return proto::parse_enum<proto::JobState>(text, proto::InputLocation::file(where));
}

proto::JobKind decode_kind(const std::string& text, const std::string& where) {
  return proto::parse_enum<proto::JobKind>(text, proto::InputLocation::file(where));
}

std::string attempts_exhausted_error(int max_attempts) {
  return proto::encode_problem(
             job_problem(ErrorKind::kAttemptsExhausted,
                         "the job's run ended without an outcome " + std::to_string(max_attempts) +
                             " times (its node stopped, crashed or lost its lease); it is not run again (resubmit "
                             "it if this was not the job's fault)"))
      .dump();
}

void require_final_state(proto::JobState state) {
  if (!proto::is_terminal(state)) {
    throw std::invalid_argument(std::string("finish: ") + proto::to_string(state) + " is not a final state");
  }
}

}  // namespace texwarp::server::store_rows
