// The declared body length of a request: see declared_length.hpp.
#include "texwarp/server/declared_length.hpp"

#include <charconv>
#include <system_error>

namespace texwarp::server {

std::optional<std::uint64_t> declared_content_length(std::string_view field) {
  if (field.empty()) return std::nullopt;
  std::uint64_t n = 0;
  const char* end = field.data() + field.size();
  const auto [at, ec] = std::from_chars(field.data(), end, n);
  if (ec != std::errc() || at != end) return std::nullopt;
  return n;
}

}  // namespace texwarp::server
