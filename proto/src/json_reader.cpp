// Strict JSON reading with paths: see json_reader.hpp.
#include "texwarp/proto/json_reader.hpp"

#include <cmath>

#include "texwarp/proto/input_error.hpp"

namespace texwarp::proto {

nlohmann::json parse_json(std::string_view text, const std::string& source) {
  try {
    return nlohmann::json::parse(text.begin(), text.end());
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(source, "not valid JSON (byte " + std::to_string(e.byte) + "): " + e.what());
  } catch (const nlohmann::json::exception& e) {  // e.g. a number too large for a double
    throw InputError(source, std::string("not valid JSON: ") + e.what());
  }
}

std::string json_key_path(const std::string& parent, std::string_view key) {
  return (parent.empty() ? std::string("$") : parent) + "." + std::string(key);
}

std::string json_index_path(const std::string& parent, std::size_t index) {
  return (parent.empty() ? std::string("$") : parent) + "[" + std::to_string(index) + "]";
}

std::string json_type_name(const nlohmann::json& value) {
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_boolean()) return "a boolean";
  if (value.is_null()) return "null";
  if (value.is_array()) return "an array";
  if (value.is_object()) return "an object";
  return value.type_name();
}

double read_finite_number(const nlohmann::json& value, const std::string& path) {
  if (!value.is_number()) throw InputError(path, "expected a number, got " + json_type_name(value));
  const double x = value.get<double>();
  if (!std::isfinite(x)) throw InputError(path, "expected a finite number");
  return x;
}

std::array<double, 2> read_point(const nlohmann::json& value, const std::string& path) {
  if (!value.is_array() || value.size() != 2) {
    throw InputError(path, "expected a point [x, y] (an array of 2 numbers), got " +
                               (value.is_array() ? "an array of " + std::to_string(value.size()) + " items"
                                                 : json_type_name(value)));
  }
  return {read_finite_number(value[0], json_index_path(path, 0)),
          read_finite_number(value[1], json_index_path(path, 1))};
}

JsonReader::JsonReader(const nlohmann::json& value, std::string path) : value_(value), path_(std::move(path)) {
  if (path_.empty()) path_ = "$";
  if (!value_.is_object()) throw InputError(path_, "expected an object, got " + json_type_name(value_));
}

bool JsonReader::has(std::string_view key) const { return value_.contains(key); }

const nlohmann::json& JsonReader::at(std::string_view key) {
  const auto it = value_.find(key);
  if (it == value_.end()) throw InputError(key_path(key), "required key is missing");
  seen_.emplace(key);
  return *it;
}

double JsonReader::number(std::string_view key) { return read_finite_number(at(key), key_path(key)); }

std::optional<double> JsonReader::optional_number(std::string_view key) {
  if (!has(key)) return std::nullopt;
  return number(key);
}

std::optional<std::string> JsonReader::optional_string(std::string_view key) {
  if (!has(key)) return std::nullopt;
  const auto& v = at(key);
  if (!v.is_string()) throw InputError(key_path(key), "expected a string, got " + json_type_name(v));
  return v.get<std::string>();
}

std::optional<long long> JsonReader::optional_integer(std::string_view key) {
  if (!has(key)) return std::nullopt;
  const auto& v = at(key);
  if (!v.is_number_integer()) throw InputError(key_path(key), "expected an integer, got " + json_type_name(v));
  return v.get<long long>();
}

std::optional<bool> JsonReader::optional_bool(std::string_view key) {
  if (!has(key)) return std::nullopt;
  const auto& v = at(key);
  if (!v.is_boolean()) throw InputError(key_path(key), "expected true or false, got " + json_type_name(v));
  return v.get<bool>();
}

void JsonReader::reject_unknown_keys() const {
  for (const auto& item : value_.items()) {
    if (seen_.find(item.key()) == seen_.end()) {
      throw InputError(json_key_path(path_, item.key()), "unknown key");
    }
  }
}

}  // namespace texwarp::proto
