// RequestTarget: an HTTP request target ("/v1/jobs/abc?limit=5") split into percent-decoded path segments and
// query pairs. Decoded bytes are returned as they are (they may not be UTF-8): callers validate what they use.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace texwarp::server {

struct RequestTarget {
  std::vector<std::string> segments;                       // non-empty path segments, percent-decoded
  std::vector<std::pair<std::string, std::string>> query;  // key, value; percent-decoded, '+' read as a space
};

// Never throws (but std::bad_alloc). Empty segments ("//") are skipped; a '%' not followed by two hex digits is
// kept as it is; a query pair without '=' has an empty value.
RequestTarget parse_request_target(std::string_view target);

}  // namespace texwarp::server
