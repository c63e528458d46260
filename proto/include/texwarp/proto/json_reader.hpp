// JsonReader: strict, path-aware reading of a JSON object for the codecs: typed getters that name the
// JSON path of any offender, and a final check that rejects keys the schema does not know.
#pragma once

#include <array>
#include <optional>
#include <set>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace texwarp::proto {

// Parses text as JSON; a syntax error becomes an InputError naming `source` (a file name, "request body"...)
// and the byte offset.
nlohmann::json parse_json(std::string_view text, const std::string& source);

// Child path helpers: "$" + ".key" / "[index]".
std::string json_key_path(const std::string& parent, std::string_view key);
std::string json_index_path(const std::string& parent, std::size_t index);

class JsonReader {
 public:
  // Throws InputError at `path` when `value` is not an object.
  JsonReader(const nlohmann::json& value, std::string path);

  const std::string& path() const { return path_; }
  bool has(std::string_view key) const;
  const nlohmann::json& at(std::string_view key);  // required key (error names it when missing)
  std::string key_path(std::string_view key) const { return json_key_path(path_, key); }

  double number(std::string_view key);                                    // required finite number
  std::optional<double> optional_number(std::string_view key);            // finite number when present
  std::optional<std::string> optional_string(std::string_view key);
  std::optional<long long> optional_integer(std::string_view key);
  std::optional<bool> optional_bool(std::string_view key);

  // Throws InputError naming the first key that was never read: unknown keys are rejected.
  void reject_unknown_keys() const;

 private:
  const nlohmann::json& value_;
  std::string path_;
  std::set<std::string, std::less<>> seen_;
};

// Free readers for values at a path.
double read_finite_number(const nlohmann::json& value, const std::string& path);
std::array<double, 2> read_point(const nlohmann::json& value, const std::string& path);  // [x, y]
std::string json_type_name(const nlohmann::json& value);

}  // namespace texwarp::proto
