// JsonReader: strict, path-aware reading of a JSON object for the codecs: typed getters that name the
// JSON path of any offender, and a final check that rejects keys the schema does not know (suggesting the near
// known key for a typo). parse_json: the one place JSON text becomes a value (depth-limited, duplicate keys refused).
#pragma once

#include <array>
#include <cstddef>
#include <initializer_list>
#include <optional>
#include <set>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

// Deepest nesting of arrays and objects parse_json accepts (a scalar at the top is depth 0, `[1]` depth 1).
inline constexpr std::size_t kMaxJsonDepth = 64;

// Well-formed JSON text whose object repeats a key. Where: the JSON path of the repeat ("$.a.b") in the source,
// detail "duplicate key". The text parses but its meaning is ambiguous, so boundaries report it as invalid content
// (like a schema error), not as malformed JSON.
class DuplicateKeyError : public InputError {
 public:
  using InputError::InputError;
};

// Parses text as JSON in one pass, time and memory proportional to its size. InputError in file `source` (a file
// name, "request body"...) with the byte offset for a syntax error or for nesting deeper than kMaxJsonDepth
// ("request body: JSON nested deeper than 64 levels (byte 65)"); DuplicateKeyError for a repeated key.
nlohmann::json parse_json(std::string_view text, const std::string& source);

class JsonReader {
 public:
  // Throws InputError at `path` when `value` is not an object.
  JsonReader(const nlohmann::json& value, JsonPath path);

  const JsonPath& path() const { return path_; }
  // Every getter and has() also records `key` as one the schema knows (for the unknown keys' suggestions).
  bool has(std::string_view key);
  const nlohmann::json& at(std::string_view key);  // required key (error names it, and a near unknown key)
  JsonPath key_path(std::string_view key) const { return path_.key(key); }

  double number(std::string_view key);                          // required finite number
  std::optional<double> optional_number(std::string_view key);  // finite number when present
  std::optional<std::string> optional_string(std::string_view key);
  std::optional<long long> optional_integer(std::string_view key);
  std::optional<bool> optional_bool(std::string_view key);

  // Declares keys of the schema that this decoding path does not read (e.g. the keys of another variant), so
  // that a typo of one of them is still recognised.
  void know_keys(std::initializer_list<std::string_view> keys);

  // A key present in the object, never read and not known to the schema, that is near `key` (a typo of it: same
  // ignoring case, or Damerau–Levenshtein distance ≤ 2, ≤ 1 when `key` has 4 characters or fewer); the closest.
  std::optional<std::string> near_unknown_key(std::string_view key) const;

  // Throws InputError naming the first key that was never read: unknown keys are rejected, with "did you mean"
  // for a near known key that is not present.
  void reject_unknown_keys() const;

 private:
  const nlohmann::json& value_;
  JsonPath path_;
  std::set<std::string, std::less<>> seen_;   // keys read
  std::set<std::string, std::less<>> known_;  // keys the schema knows (asked for or declared)
};

// `key` (user text) as a JSON string for a message: cut to kMaxKeyShown bytes between characters, escaped.
std::string quoted_key(std::string_view key);

// Free readers for values at a path.
double read_finite_number(const nlohmann::json& value, const JsonPath& path);
std::array<double, 2> read_point(const nlohmann::json& value, const JsonPath& path);  // [x, y]
std::string json_type_name(const nlohmann::json& value);

}  // namespace texwarp::proto
