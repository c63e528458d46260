// Base64 (RFC 4648, standard alphabet, with padding) for images inline in a job: strict decoding that names
// the JSON path and byte offset of the first character that does not belong.
#pragma once

#include <string>
#include <string_view>

#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {

std::string base64_encode(std::string_view bytes);

// Whitespace (space, tab, CR, LF) is skipped; anything else outside the alphabet, a misplaced '=' or a length
// that is not a whole number of quanta is an InputError at `path`.
std::string base64_decode(std::string_view text, const JsonPath& path);

}  // namespace texwarp::proto
