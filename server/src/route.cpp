// Route lookup: see route.hpp.
#include "texwarp/server/route.hpp"

#include <algorithm>
#include <stdexcept>

namespace texwarp::server {

const std::string& RouteParams::operator[](std::string_view name) const {
  for (const auto& [n, v] : values_) {
    if (n == name) return v;
  }
  throw std::out_of_range("no route parameter " + std::string(name));
}

std::optional<RouteParams> match_pattern(std::string_view pattern, const std::vector<std::string>& segments) {
  RouteParams params;
  std::size_t i = 0;
  std::size_t start = 1;  // after the leading '/'
  while (start <= pattern.size()) {
    const auto slash = pattern.find('/', start);
    const std::string_view part =
        pattern.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
    if (i >= segments.size()) return std::nullopt;
    const auto close = part.starts_with('{') ? part.find('}') : std::string_view::npos;
    if (close != std::string_view::npos && close > 1) {
      // "{name}" takes the whole segment; "{name}:verb" a segment that ends in ":verb", the rest non-empty.
      const std::string_view suffix = part.substr(close + 1);
      const std::string& segment = segments[i];
      if (!std::string_view(segment).ends_with(suffix) || (!suffix.empty() && segment.size() == suffix.size())) {
        return std::nullopt;
      }
      params.add(part.substr(1, close - 1), segment.substr(0, segment.size() - suffix.size()));
    } else if (part != segments[i]) {
      return std::nullopt;
    }
    ++i;
    if (slash == std::string_view::npos) break;
    start = slash + 1;
  }
  if (i != segments.size()) return std::nullopt;
  return params;
}

RouteLookup find_route(std::span<const Route> table, http::verb method, const std::vector<std::string>& segments) {
  RouteLookup out;
  for (const Route& row : table) {
    auto params = match_pattern(row.pattern, segments);
    if (!params) continue;
    if (out.path_route == nullptr) out.path_route = &row;
    for (const http::verb m : row.methods) {
      if (std::find(out.allowed.begin(), out.allowed.end(), m) == out.allowed.end()) out.allowed.push_back(m);
    }
    if (out.route == nullptr && std::find(row.methods.begin(), row.methods.end(), method) != row.methods.end()) {
      out.route = &row;
      out.params = std::move(*params);
    }
  }
  return out;
}

std::string allow_header(const std::vector<http::verb>& methods) {
  std::string out;
  for (const http::verb m : methods) {
    if (!out.empty()) out += ", ";
    out += std::string(http::to_string(m));
  }
  return out;
}

}  // namespace texwarp::server
