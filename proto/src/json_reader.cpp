// Strict JSON reading with paths: see json_reader.hpp.
#include "texwarp/proto/json_reader.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <iterator>
#include <limits>
#include <utility>
#include <variant>
#include <vector>

#include "texwarp/proto/utf8_text.hpp"

namespace texwarp::proto {
namespace {

using Json = nlohmann::json;

// A pointer into the text that publishes how far the parser has read, so that the SAX handler (which is told no
// positions) can name the byte of the bracket that nests too deep.
class TrackedChar {
 public:
  using iterator_category = std::input_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;

  TrackedChar(const char* at, const char** read_up_to) : at_(at), read_up_to_(read_up_to) {}
  reference operator*() const { return *at_; }
  TrackedChar& operator++() {
    *read_up_to_ = ++at_;
    return *this;
  }
  TrackedChar operator++(int) {
    TrackedChar before = *this;
    ++*this;
    return before;
  }
  bool operator==(const TrackedChar& other) const { return at_ == other.at_; }
  bool operator!=(const TrackedChar& other) const { return at_ != other.at_; }

 private:
  const char* at_;
  const char** read_up_to_;
};

// SAX events → a DOM, refusing (at the first offending event, so the work done is bounded by the text read so far)
// nesting deeper than kMaxJsonDepth and a key repeated in one object.
class DomBuilder {
 public:
  DomBuilder(Json& root, const std::string& source, const char* text, const char* const* read_up_to)
      : root_(root), source_(source), text_(text), read_up_to_(read_up_to) {}

  bool null() { return put(Json(nullptr)); }
  bool boolean(bool v) { return put(Json(v)); }
  bool number_integer(Json::number_integer_t v) { return put(Json(v)); }
  bool number_unsigned(Json::number_unsigned_t v) { return put(Json(v)); }
  bool number_float(Json::number_float_t v, const Json::string_t&) { return put(Json(v)); }
  bool string(Json::string_t& v) { return put(Json(std::move(v))); }
  bool binary(Json::binary_t& v) { return put(Json::binary(std::move(v))); }

  bool start_object(std::size_t) { return open(Json::value_t::object); }
  bool start_array(std::size_t) { return open(Json::value_t::array); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }

  bool key(Json::string_t& name) {
    Level& level = levels_.back();
    auto& members = level.value->get_ref<Json::object_t&>();
    auto [it, inserted] = members.try_emplace(std::move(name));
    if (!inserted) {
      error_.emplace<DuplicateKeyError>(InputLocation(path_to(levels_.size() - 1).key(it->first)).in_file(source_),
                                        "duplicate key");
      return false;
    }
    level.key = &it->first;
    slot_ = &it->second;
    return true;
  }

  bool parse_error(std::size_t byte, const std::string&, const nlohmann::detail::exception& e) {
    error_.emplace<InputError>(InputLocation::file(source_),
                               "not valid JSON (byte " + std::to_string(byte) + "): " + e.what());
    return false;
  }

  // The refusal recorded by a failed parse.
  [[noreturn]] void rethrow() const {
    if (const auto* d = std::get_if<DuplicateKeyError>(&error_)) throw *d;
    if (const auto* e = std::get_if<InputError>(&error_)) throw *e;
    throw InputError(InputLocation::file(source_), "not valid JSON");
  }

 private:
  struct Level {
    Json* value;                       // the open array or object
    const std::string* key = nullptr;  // for an object: the key whose value is being read
  };

  Json* place(Json&& v) {
    if (levels_.empty()) {
      root_ = std::move(v);
      return &root_;
    }
    Json* parent = levels_.back().value;
    if (parent->is_array()) {
      auto& items = parent->get_ref<Json::array_t&>();
      items.push_back(std::move(v));
      return &items.back();
    }
    *slot_ = std::move(v);
    return slot_;
  }

  bool put(Json&& v) {
    place(std::move(v));
    return true;
  }

  bool open(Json::value_t type) {
    if (levels_.size() == kMaxJsonDepth) {
      const std::string byte = std::to_string(*read_up_to_ - text_);
      error_.emplace<InputError>(InputLocation::file(source_), "JSON nested deeper than " +
                                                                   std::to_string(kMaxJsonDepth) + " levels (byte " +
                                                                   byte + ")");
      return false;
    }
    levels_.push_back({place(Json(type))});
    return true;
  }

  bool close() {
    levels_.pop_back();
    return true;
  }

  // The JSON path of the container open at `depth` (0: the root).
  JsonPath path_to(std::size_t depth) const {
    JsonPath path;
    for (std::size_t i = 0; i < depth; ++i) {
      const Level& level = levels_[i];
      path = level.value->is_array() ? path.index(level.value->size() - 1) : path.key(*level.key);
    }
    return path;
  }

  Json& root_;
  const std::string& source_;
  const char* text_;
  const char* const* read_up_to_;
  std::vector<Level> levels_;
  Json* slot_ = nullptr;  // the member value the next event fills, inside the innermost object
  std::variant<std::monostate, InputError, DuplicateKeyError> error_;
};

char lower_ascii(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

// Damerau–Levenshtein distance (optimal string alignment: adjacent transpositions count 1) of the ASCII-lowercased
// strings; any value above `limit` comes out as limit + 1.
std::size_t key_distance(std::string_view a, std::string_view b, std::size_t limit) {
  const std::size_t n = a.size();
  const std::size_t m = b.size();
  if ((n > m ? n - m : m - n) > limit) return limit + 1;
  std::vector<std::size_t> prev2(m + 1), prev(m + 1), row(m + 1);
  for (std::size_t j = 0; j <= m; ++j) prev[j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    row[0] = i;
    std::size_t best = row[0];
    for (std::size_t j = 1; j <= m; ++j) {
      const bool same = lower_ascii(a[i - 1]) == lower_ascii(b[j - 1]);
      row[j] = std::min({prev[j] + 1, row[j - 1] + 1, prev[j - 1] + (same ? 0 : 1)});
      if (i > 1 && j > 1 && lower_ascii(a[i - 1]) == lower_ascii(b[j - 2]) &&
          lower_ascii(a[i - 2]) == lower_ascii(b[j - 1])) {
        row[j] = std::min(row[j], prev2[j - 2] + 1);
      }
      best = std::min(best, row[j]);
    }
    if (best > limit) return limit + 1;
    std::swap(prev2, prev);
    std::swap(prev, row);
  }
  return std::min(prev[m], limit + 1);
}

// How far a typo of `known` may be from it.
std::size_t typo_limit(std::string_view known) { return known.size() <= 4 ? 1 : 2; }

}  // namespace

nlohmann::json parse_json(std::string_view text, const std::string& source) {
  Json root;
  const char* read_up_to = text.data();
  DomBuilder builder(root, source, text.data(), &read_up_to);
  const TrackedChar first(text.data(), &read_up_to);
  const TrackedChar last(text.data() + text.size(), &read_up_to);
  if (!Json::sax_parse(first, last, &builder)) builder.rethrow();
  return root;
}

std::string quoted_key(std::string_view key) { return safe_dump(Json(utf8_prefix(key, kMaxKeyShown))); }

std::string json_type_name(const nlohmann::json& value) {
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_boolean()) return "a boolean";
  if (value.is_null()) return "null";
  if (value.is_array()) return "an array";
  if (value.is_object()) return "an object";
  return value.type_name();
}

double read_finite_number(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_number()) throw InputError(path, "expected a number, got " + json_type_name(value));
  const double x = value.get<double>();
  if (!std::isfinite(x)) throw InputError(path, "expected a finite number");
  return x;
}

std::array<double, 2> read_point(const nlohmann::json& value, const JsonPath& path) {
  if (!value.is_array() || value.size() != 2) {
    throw InputError(path, "expected a point [x, y] (an array of 2 numbers), got " +
                               (value.is_array() ? "an array of " + std::to_string(value.size()) + " items"
                                                 : json_type_name(value)));
  }
  return {read_finite_number(value[0], path.index(0)), read_finite_number(value[1], path.index(1))};
}

JsonReader::JsonReader(const nlohmann::json& value, JsonPath path) : value_(value), path_(std::move(path)) {
  if (!value_.is_object()) throw InputError(path_, "expected an object, got " + json_type_name(value_));
}

bool JsonReader::has(std::string_view key) {
  known_.emplace(key);
  return value_.contains(key);
}

const nlohmann::json& JsonReader::at(std::string_view key) {
  known_.emplace(key);
  const auto it = value_.find(key);
  if (it == value_.end()) {
    const auto near = near_unknown_key(key);
    const std::string note = near ? " (there is an unknown key " + quoted_key(*near) + ")" : std::string();
    throw InputError(key_path(key), "required key is missing" + note);
  }
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
  if (v.is_number_unsigned() && v.get<unsigned long long>() > static_cast<unsigned long long>(LLONG_MAX)) {
    throw InputError(key_path(key), "the integer " + v.dump() + " is out of range");
  }
  return v.get<long long>();
}

std::optional<bool> JsonReader::optional_bool(std::string_view key) {
  if (!has(key)) return std::nullopt;
  const auto& v = at(key);
  if (!v.is_boolean()) throw InputError(key_path(key), "expected true or false, got " + json_type_name(v));
  return v.get<bool>();
}

void JsonReader::know_keys(std::initializer_list<std::string_view> keys) {
  for (const auto key : keys) known_.emplace(key);
}

std::optional<std::string> JsonReader::near_unknown_key(std::string_view key) const {
  const std::size_t limit = typo_limit(key);
  std::optional<std::string> best;
  std::size_t best_distance = limit + 1;
  for (const auto& item : value_.items()) {
    const std::string& given = item.key();
    if (seen_.count(given) != 0 || known_.count(given) != 0) continue;
    const std::size_t d = key_distance(given, key, limit);
    if (d < best_distance) {
      best_distance = d;
      best = given;
    }
  }
  return best;
}

void JsonReader::reject_unknown_keys() const {
  for (const auto& item : value_.items()) {
    const std::string& given = item.key();
    if (seen_.count(given) != 0) continue;
    std::string suggestion;
    std::size_t best_distance = std::numeric_limits<std::size_t>::max();
    for (const auto& known : known_) {
      if (known == given || value_.contains(known)) continue;
      const std::size_t limit = typo_limit(known);
      const std::size_t d = key_distance(given, known, limit);
      if (d <= limit && d < best_distance) {
        best_distance = d;
        suggestion = known;
      }
    }
    throw InputError(path_.key(given),
                     suggestion.empty() ? "unknown key" : "unknown key; did you mean \"" + suggestion + "\"?");
  }
}

}  // namespace texwarp::proto
