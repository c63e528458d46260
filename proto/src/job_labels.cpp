// Job labels: see job_labels.hpp.
#include "texwarp/proto/job_labels_codec.hpp"

#include <algorithm>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/utf8_text.hpp"

namespace texwarp::proto {
namespace {

bool is_key_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
         c == '-' || c == '/';
}

}  // namespace

void check_job_label(const std::string& key, const std::string& value, const InputLocation& key_at,
                     const InputLocation& value_at) {
  if (key.empty()) throw InputError(key_at, "a label key cannot be empty");
  if (key.size() > kMaxLabelKeyLength) {
    throw InputError(key_at, "a label key is at most " + std::to_string(kMaxLabelKeyLength) + " characters, got " +
                                 std::to_string(key.size()));
  }
  if (!std::all_of(key.begin(), key.end(), is_key_char)) {
    throw InputError(key_at, "a label key " + quoted_key(key) + " may hold only A-Z a-z 0-9 _ . - /");
  }
  if (value.size() > kMaxLabelValueLength) {
    throw InputError(value_at, "a label value is at most " + std::to_string(kMaxLabelValueLength) + " bytes, got " +
                                   std::to_string(value.size()));
  }
  if (!is_valid_utf8(value)) throw InputError(value_at, "a label value must be UTF-8 text");
  if (has_control_characters(value)) {
    throw InputError(value_at, "a label value cannot hold control characters (U+0000–U+001F, U+007F)");
  }
}

JobLabels decode_job_labels(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_object()) throw InputError(path, "expected an object of string values, got " + json_type_name(value));
  if (value.size() > kMaxJobLabels) {
    throw InputError(path, "at most " + std::to_string(kMaxJobLabels) + " labels, got " + std::to_string(value.size()));
  }
  JobLabels labels;
  for (const auto& [key, v] : value.items()) {
    const JsonPath at = path.key(key);
    if (!v.is_string()) throw InputError(at, "expected a string, got " + json_type_name(v));
    const std::string text = v.get<std::string>();
    check_job_label(key, text, at, at);
    labels.emplace(key, text);
  }
  return labels;
}

nlohmann::json encode_job_labels(const JobLabels& labels) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [k, v] : labels) out[k] = v;
  return out;
}

}  // namespace texwarp::proto
