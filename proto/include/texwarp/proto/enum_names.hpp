// The wire names of the contract's enums: each enum's names are stated once, in its EnumNames table (next to the
// enum), and every decoder, encoder, message and CLI choice list is derived from that table.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "texwarp/proto/input_error.hpp"

namespace texwarp::proto {

// Specialised for each wire enum E: `static constexpr std::array<std::pair<E, const char*>, N> kTable`, every
// enumerator once, in the order messages list them.
template <typename E>
struct EnumNames;

template <typename E>
concept WireEnum = requires {
  EnumNames<E>::kTable;
};

// The wire name of `value`.
template <WireEnum E>
constexpr const char* to_string(E value) {
  for (const auto& [v, name] : EnumNames<E>::kTable) {
    if (v == value) return name;
  }
  return "?";
}

// The value named `name`, if any.
template <WireEnum E>
constexpr std::optional<E> enum_from_name(std::string_view name) {
  for (const auto& [v, n] : EnumNames<E>::kTable) {
    if (name == n) return v;
  }
  return std::nullopt;
}

// Every name, in table order (for CLI choice lists).
template <WireEnum E>
std::vector<std::string> enum_names() {
  std::vector<std::string> names;
  for (const auto& entry : EnumNames<E>::kTable) names.emplace_back(entry.second);
  return names;
}

// `"a", "b" or "c"`: the names for a message.
template <WireEnum E>
std::string quoted_enum_names() {
  const auto& table = EnumNames<E>::kTable;
  std::string out;
  for (std::size_t i = 0; i < table.size(); ++i) {
    if (i > 0) out += (i + 1 == table.size()) ? " or " : ", ";
    out += std::string("\"") + table[i].second + "\"";
  }
  return out;
}

// The value named `name`; InputError at `where` ("expected "a", "b" or "c", got "x"") otherwise.
template <WireEnum E>
E parse_enum(std::string_view name, const InputLocation& where) {
  if (const auto v = enum_from_name<E>(name)) return *v;
  throw InputError(where, "expected " + quoted_enum_names<E>() + ", got \"" + std::string(name.substr(0, 80)) + "\"");
}

}  // namespace texwarp::proto
