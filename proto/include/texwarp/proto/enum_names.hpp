// The wire names of the contract's enums: each enum's names are stated once, in its EnumNames table (next to the
// enum), and every decoder, encoder, message and CLI choice list is derived from that table.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "texwarp/proto/input_error.hpp"

namespace texwarp::proto {

// Specialised for each wire enum E: `static constexpr std::array<std::pair<E, const char*>, N> kTable`, every
// enumerator once, in the order messages list them.
template <typename E>
struct EnumNames;

// Whether E has an EnumNames table: a trait (C++17, as the installed headers must be) that the functions below
// take as their constraint; C++20 code may say WireEnum<E>.
template <typename E, typename = void>
struct IsWireEnum : std::false_type {};
template <typename E>
struct IsWireEnum<E, std::void_t<decltype(EnumNames<E>::kTable)>> : std::true_type {};
// The constraint of the functions below: they take part in overload resolution for wire enums only.
template <typename E>
using EnableIfWireEnum = std::enable_if_t<IsWireEnum<E>::value, int>;

#if defined(__cpp_concepts)
template <typename E>
concept WireEnum = IsWireEnum<E>::value;
#endif

// The wire name of `value`.
template <typename E, EnableIfWireEnum<E> = 0>
constexpr const char* to_string(E value) {
  for (const auto& [v, name] : EnumNames<E>::kTable) {
    if (v == value) return name;
  }
  return "?";
}

// The value named `name`, if any.
template <typename E, EnableIfWireEnum<E> = 0>
constexpr std::optional<E> enum_from_name(std::string_view name) {
  for (const auto& [v, n] : EnumNames<E>::kTable) {
    if (name == n) return v;
  }
  return std::nullopt;
}

// Every name, in table order (for CLI choice lists).
template <typename E, EnableIfWireEnum<E> = 0>
std::vector<std::string> enum_names() {
  std::vector<std::string> names;
  names.reserve(EnumNames<E>::kTable.size());
  for (const auto& entry : EnumNames<E>::kTable) names.emplace_back(entry.second);
  return names;
}

// `"a", "b" or "c"`: the names for a message.
template <typename E, EnableIfWireEnum<E> = 0>
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
template <typename E, EnableIfWireEnum<E> = 0>
E parse_enum(std::string_view name, const InputLocation& where) {
  if (const auto v = enum_from_name<E>(name)) return *v;
  throw InputError(where, "expected " + quoted_enum_names<E>() + ", got \"" + std::string(name.substr(0, 80)) + "\"");
}

}  // namespace texwarp::proto
