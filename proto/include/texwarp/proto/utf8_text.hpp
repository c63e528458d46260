// Text that leaves the program (HTTP bodies, problem details, log lines) is valid UTF-8 by construction: JSON is
// serialised with invalid bytes replaced (U+FFFD) and never throws, and user text is cut only between characters.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace texwarp::proto {

// `value` as JSON text (compact when indent < 0); bytes that are not UTF-8 in any string become U+FFFD. Never
// throws a JSON error (only std::bad_alloc).
std::string safe_dump(const nlohmann::json& value, int indent = -1);

// True when `text` is well-formed UTF-8 (no overlongs, no surrogates, nothing above U+10FFFF).
bool is_valid_utf8(std::string_view text);

// True when the text holds a control character (U+0000–U+001F or U+007F): names and labels are one line of text,
// and a NUL would be cut off by a database that stores C strings (libpq).
bool has_control_characters(std::string_view text);

// `text` with every ill-formed byte sequence replaced by U+FFFD.
std::string to_valid_utf8(std::string_view text);

// The longest prefix of `text` of at most `max_bytes` bytes that does not end inside a multi-byte character,
// made valid UTF-8 (as to_valid_utf8); "…" is appended when anything was cut.
std::string utf8_prefix(std::string_view text, std::size_t max_bytes);

}  // namespace texwarp::proto
